#include "geo/index_georeference.h"

#include <cstring>

namespace cwloc {

Georeference GeoreferenceOfSection(const IndexGeoreference& section) {
  Georeference georeference;
  georeference.origin = {section.origin_latitude_deg, section.origin_longitude_deg,
                         section.origin_height_m};
  georeference.scale = section.scale;
  georeference.rotation = Eigen::Quaterniond(section.rotation[0], section.rotation[1],
                                             section.rotation[2], section.rotation[3])
                              .normalized();
  georeference.translation = {section.translation[0], section.translation[1],
                              section.translation[2]};
  return georeference;
}

Eigen::Vector3d CameraCenterOf(const IndexImage& image) {
  const Eigen::Quaterniond q(image.cam_from_world_rotation[0], image.cam_from_world_rotation[1],
                             image.cam_from_world_rotation[2], image.cam_from_world_rotation[3]);
  const Eigen::Vector3d t(image.cam_from_world_translation[0], image.cam_from_world_translation[1],
                          image.cam_from_world_translation[2]);
  return -(q.normalized().conjugate() * t);
}

IndexGeoreference SectionOfGeoreference(const Georeference& georeference) {
  IndexGeoreference section;
  std::memset(&section, 0, sizeof(section));
  section.origin_latitude_deg = georeference.origin.latitude_deg;
  section.origin_longitude_deg = georeference.origin.longitude_deg;
  section.origin_height_m = georeference.origin.height_m;
  section.scale = georeference.scale;
  const Eigen::Quaterniond q = georeference.rotation.normalized();
  section.rotation[0] = q.w();
  section.rotation[1] = q.x();
  section.rotation[2] = q.y();
  section.rotation[3] = q.z();
  for (int i = 0; i < 3; ++i) section.translation[i] = georeference.translation[i];
  return section;
}

}  // namespace cwloc

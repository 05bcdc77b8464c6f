// cwloc-index build --georef / --model-frame: the GEOR section and the manifest's georeference.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "format/index.h"
#include "geo/index_georeference.h"
#include "tests/indexer/indexer_fixture.h"
#include "tests/photo/exif_builder.h"

namespace cwloc {
namespace {

class GeoreferencingTest : public test::IndexerFixture {
 protected:
  static Eigen::Vector3d Center(const colmap::Image& image) {
    const std::array<double, 3> c = colmap::Inverse(image.cam_from_world).translation;
    return {c[0], c[1], c[2]};
  }

  // A similarity the fit must recover, and the WGS84 origin of its ENU frame.
  Georeference Truth() const {
    Georeference truth;
    truth.origin = {48.8566, 2.3522, 35.0};
    truth.scale = 3.7;
    truth.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.8, Eigen::Vector3d(1, 2, 3).normalized()));
    truth.translation = {120.0, -40.0, 2.0};
    return truth;
  }

  // Writes every model image's exact position under Truth().
  std::filesystem::path WriteGeorefFile(const std::string& extra_line = "") const {
    const GeoFrame frame(Truth());
    const std::filesystem::path path = dir_ / "georef.txt";
    std::ofstream out(path);
    out << "# IMAGE_NAME LAT LON HEIGHT\n";
    for (const auto& [id, image] : model_.images) {
      const Eigen::Vector3d center = Center(image);
      const Geodetic g = frame.ModelToGeodetic(center);
      char line[256];
      std::snprintf(line, sizeof(line), "%s %.12f %.12f %.6f\n", image.name.c_str(), g.latitude_deg,
                    g.longitude_deg, g.height_m);
      out << line;
    }
    out << extra_line;
    return path;
  }

  void Build(const GeoreferencingOptions& georeferencing) const {
    IndexBuildOptions options;
    options.model_dir = model_dir_;
    options.database_path = database_path_;
    options.output_path = index_path_;
    options.georeferencing = georeferencing;
    BuildIndex(options);
  }

  std::string BuildError(const GeoreferencingOptions& georeferencing) const {
    try {
      Build(georeferencing);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(GeoreferencingTest, AGeorefFileIsFitExactlyAndStoredInSectionAndManifest) {
  GeoreferencingOptions options;
  options.georef_file = WriteGeorefFile();
  Build(options);
  const Index index = Index::Open(index_path_);
  ASSERT_NE(index.georeference(), nullptr);
  const IndexGeoreference& section = *index.georeference();
  EXPECT_EQ(section.source, static_cast<uint32_t>(GeoreferenceSource::kFile));
  EXPECT_EQ(section.num_observations, model_.images.size());
  EXPECT_EQ(section.num_inliers, model_.images.size());
  EXPECT_LT(section.rms_residual_m, 1e-4);
  EXPECT_NEAR(section.scale, Truth().scale, 1e-7);

  // Every camera centre lands on its true position through the stored georeference.
  const GeoFrame stored(GeoreferenceOfSection(section));
  const GeoFrame truth(Truth());
  for (const auto& [id, image] : model_.images) {
    const Eigen::Vector3d center = Center(image);
    const Eigen::Vector3d expected = stored.GeodeticToEnu(truth.ModelToGeodetic(center));
    EXPECT_LT((stored.georeference().ModelToEnu(center) - expected).norm(), 1e-3) << image.name;
  }

  const auto manifest = nlohmann::json::parse(index.manifest_json());
  EXPECT_EQ(manifest["format_version"], "1.5");  // GEOR is 1.1's, PCAL 1.3's, PIDS 1.5's
  const auto& georeference = manifest["georeference"];
  EXPECT_EQ(georeference["source"], "georef-file");
  EXPECT_EQ(georeference["path"], options.georef_file.string());
  EXPECT_EQ(georeference["fit"]["inliers"], model_.images.size());
  EXPECT_TRUE(georeference["fit"]["outliers"].empty());
  EXPECT_DOUBLE_EQ(georeference["scale"].get<double>(), section.scale);
}

// EXIF stores degrees, minutes and hundredths of seconds (0.3 m of latitude) and altitude in
// centimetres; the first photo has no fix and is counted, not used.
TEST_F(GeoreferencingTest, TheExifGpsOfThePhotosIsFit) {
  const GeoFrame truth(Truth());
  const auto photos = dir_ / "photos";
  std::filesystem::create_directories(photos);
  auto dms = [](double degrees) {
    const double a = std::abs(degrees);
    const uint32_t d = static_cast<uint32_t>(a);
    const uint32_t m = static_cast<uint32_t>((a - d) * 60);
    const uint32_t centi = static_cast<uint32_t>(std::lround(((a - d) * 60 - m) * 6000));
    return std::array<uint32_t, 3>{d, m, centi};
  };
  size_t written = 0;
  for (const auto& [id, image] : model_.images) {
    test::ExifBuilder exif;
    if (written++ > 0) {
      const Geodetic g = truth.ModelToGeodetic(Center(image));
      const auto lat = dms(g.latitude_deg), lon = dms(g.longitude_deg);
      exif.GpsPosition(g.latitude_deg >= 0 ? "N" : "S", lat[0], lat[1], lat[2],
                       g.longitude_deg >= 0 ? "E" : "W", lon[0], lon[1], lon[2])
          .GpsRationals(EXIF_TAG_GPS_ALTITUDE,
                        {{static_cast<uint32_t>(std::lround(std::abs(g.height_m) * 100)), 100}})
          .GpsByte(EXIF_TAG_GPS_ALTITUDE_REF, g.height_m >= 0 ? 0 : 1);
    }
    const std::vector<uint8_t> jpeg = exif.Jpeg();
    std::filesystem::create_directories((photos / image.name).parent_path());  // "cam1/img_1.jpg"
    std::ofstream(photos / image.name, std::ios::binary)
        .write(reinterpret_cast<const char*>(jpeg.data()),
               static_cast<std::streamsize>(jpeg.size()));
  }
  GeoreferencingOptions options;
  options.images_dir = photos;
  Build(options);
  const Index index = Index::Open(index_path_);
  ASSERT_NE(index.georeference(), nullptr);
  const IndexGeoreference& section = *index.georeference();
  EXPECT_EQ(section.source, static_cast<uint32_t>(GeoreferenceSource::kExifGps));
  EXPECT_EQ(section.num_observations, model_.images.size() - 1);
  EXPECT_EQ(section.num_inliers, model_.images.size() - 1);
  EXPECT_LT(section.rms_residual_m, 0.3);
  EXPECT_NEAR(section.scale, Truth().scale, 0.01 * Truth().scale);
  const auto manifest = nlohmann::json::parse(index.manifest_json())["georeference"];
  EXPECT_EQ(manifest["source"], "exif-gps");
  EXPECT_EQ(manifest["fit"]["images_without_gps"], 1);

  // A model image without its photo is an error naming the file.
  std::filesystem::remove(photos / model_.images.begin()->second.name);
  const std::string error = BuildError(options);
  EXPECT_NE(error.find((photos / model_.images.begin()->second.name).string()), std::string::npos)
      << error;
}

TEST_F(GeoreferencingTest, WithoutAGeoreferenceThereIsNoSectionAndTheManifestSaysNull) {
  BuildFixtureIndex();
  const Index index = Index::Open(index_path_);
  EXPECT_EQ(index.georeference(), nullptr);
  EXPECT_TRUE(nlohmann::json::parse(index.manifest_json())["georeference"].is_null());
}

TEST_F(GeoreferencingTest, AnEnuModelFrameIsStoredAsGiven) {
  GeoreferencingOptions options;
  options.model_frame = "enu:-33.8688,151.2093,12.5";
  Build(options);
  const Index index = Index::Open(index_path_);
  ASSERT_NE(index.georeference(), nullptr);
  const IndexGeoreference& g = *index.georeference();
  EXPECT_EQ(g.source, static_cast<uint32_t>(GeoreferenceSource::kEnuModel));
  EXPECT_DOUBLE_EQ(g.origin_latitude_deg, -33.8688);
  EXPECT_DOUBLE_EQ(g.origin_longitude_deg, 151.2093);
  EXPECT_DOUBLE_EQ(g.origin_height_m, 12.5);
  EXPECT_DOUBLE_EQ(g.scale, 1.0);
  EXPECT_DOUBLE_EQ(g.rotation[0], 1.0);
  EXPECT_EQ(nlohmann::json::parse(index.manifest_json())["georeference"]["model_frame"],
            "enu:-33.8688,151.2093,12.5");
}

TEST_F(GeoreferencingTest, BadGeoreferencesAreClearErrors) {
  GeoreferencingOptions two;
  two.georef_file = WriteGeorefFile();
  two.model_frame = "ecef";
  EXPECT_EQ(BuildError(two),
            "--georef, --georef-images and --model-frame exclude each other; give one");

  GeoreferencingOptions unknown;
  unknown.georef_file = WriteGeorefFile("nope.jpg 48.0 2.0 30.0\n");
  EXPECT_EQ(BuildError(unknown),
            unknown.georef_file.string() + ": image 'nope.jpg' is not in the model");

  GeoreferencingOptions ecef;
  ecef.model_frame = "ecef";
  EXPECT_EQ(BuildError(ecef).rfind("--model-frame ecef: the cameras' centroid is ", 0), 0u)
      << BuildError(ecef);

  GeoreferencingOptions frame;
  frame.model_frame = "enu:95,2,0";
  EXPECT_NE(BuildError(frame).find("--model-frame 'enu:95,2,0'"), std::string::npos)
      << BuildError(frame);
  frame.model_frame = "utm";
  EXPECT_EQ(BuildError(frame), "--model-frame 'utm': expected ecef or enu:LAT,LON,HEIGHT");

  GeoreferencingOptions sigma;
  sigma.georef_file = WriteGeorefFile();
  sigma.fit.default_sigma_m = 0;
  EXPECT_EQ(BuildError(sigma), "--georef-sigma 0: expected a number of metres > 0");
  EXPECT_FALSE(std::filesystem::exists(index_path_));
}

TEST_F(GeoreferencingTest, ACorruptGeoreferenceSectionIsRefusedAtOpen) {
  GeoreferencingOptions options;
  options.georef_file = WriteGeorefFile();
  Build(options);
  uint64_t offset = 0;
  {
    const Index index = Index::Open(index_path_);
    offset = index.file().FindSection(section::kGeoreference)->offset;
  }
  // scale := 0 (offset 24 in IndexGeoreference).
  std::fstream file(index_path_, std::ios::in | std::ios::out | std::ios::binary);
  file.seekp(static_cast<std::streamoff>(offset + 24));
  const double zero = 0;
  file.write(reinterpret_cast<const char*>(&zero), sizeof(zero));
  file.close();
  try {
    Index::Open(index_path_);
    FAIL() << "opened";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              index_path_.string() + ": section 'GEOR': scale 0.000000 is not positive");
  }
}

}  // namespace
}  // namespace cwloc

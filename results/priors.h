// A query's priors: as a caller gives them, and what they did (results/describe.h).
#ifndef CWLOC_RESULTS_PRIORS_H_
#define CWLOC_RESULTS_PRIORS_H_

#include <array>
#include <optional>

#include "describe.h"

namespace cwloc {

// Within radius_m of a WGS84 position, horizontally when the height is unknown: a query's
// position prior, and the part of a city `cwloc-index extract --near` keeps (geo/geo_region.h).
struct GeoRegion {
  double latitude_deg = 0;
  double longitude_deg = 0;        // east
  std::optional<double> height_m;  // above the WGS84 ellipsoid (not above sea level)
  double radius_m = 0;
};

// Where a query's position prior came from.
enum class PriorSource : int { kOption, kFile, kExif };
template <>
struct EnumNames<PriorSource> {
  static constexpr std::array<std::string_view, 3> names = {"option", "priors-file", "exif"};
};

// A GPS fix: the query was taken in this region; only clusters with a model camera in it are
// matched. Needs a georeferenced index.
struct PositionPrior : GeoRegion {
  PriorSource source = PriorSource::kOption;
};

// The position prior a query used, and what it did.
struct PositionPriorUse : PositionPrior {
  uint32_t clusters_in_radius = 0;
};

// The gravity prior a query used: the direction gravity pulls in the camera frame (x right, y
// down, z forward).
struct GravityPriorUse {
  std::array<double, 3> direction{};
  std::optional<double> error_deg;  // from the localized pose's gravity, on success
};

struct PriorsUsed {
  std::optional<PositionPriorUse> position;
  std::optional<GravityPriorUse> gravity;
};

namespace prior_fields {
inline constexpr auto kLatitude =
    MakeField(&GeoRegion::latitude_deg, Info("latitude_deg").Json("latitude_deg").Unit("deg"));
inline constexpr auto kLongitude =
    MakeField(&GeoRegion::longitude_deg, Info("longitude_deg").Json("longitude_deg").Unit("deg"));
inline constexpr auto kHeight =
    MakeField(&GeoRegion::height_m, Info("height_m")
                                        .Json("height_m")
                                        .Unit("m")
                                        .Help("Above the WGS84 ellipsoid; none: the radius is "
                                              "horizontal")
                                        .NullWhenAbsent());
inline constexpr auto kRadius =
    MakeField(&GeoRegion::radius_m, Info("radius_m").Json("radius_m").Unit("m"));
inline constexpr auto kSource =
    MakeField(&PositionPrior::source,
              Info("source").Json("source").Help("--prior-position (or the API's), a --priors "
                                                 "file, or the photo's EXIF GPS"));
}  // namespace prior_fields

template <>
struct Description<PositionPrior> {
  static constexpr std::string_view name = "PositionPrior";
  static constexpr std::string_view help =
      "A GPS fix: the query was taken within radius_m of this WGS84 position";
  static constexpr auto fields =
      std::tuple(prior_fields::kLatitude, prior_fields::kLongitude, prior_fields::kHeight,
                 prior_fields::kRadius, prior_fields::kSource);
};

template <>
struct Description<PositionPriorUse> {
  static constexpr std::string_view name = "PositionPriorUse";
  static constexpr std::string_view help = "The position prior a query used, and what it did";
  static constexpr auto fields = std::tuple(
      prior_fields::kLatitude, prior_fields::kLongitude, prior_fields::kHeight,
      prior_fields::kRadius, prior_fields::kSource,
      MakeField(
          &PositionPriorUse::clusters_in_radius,
          Info("clusters_in_radius")
              .Json("clusters_in_radius")
              .Help("Clusters with a model camera within the radius: the only ones matched")));
};

template <>
struct Description<GravityPriorUse> {
  static constexpr std::string_view name = "GravityPriorUse";
  static constexpr std::string_view help = "The gravity prior a query used";
  static constexpr auto fields = std::tuple(
      MakeField(&GravityPriorUse::direction,
                Info("direction")
                    .Json("direction")
                    .Help("The direction gravity pulls in the camera frame (x right, y down, z "
                          "forward)")),
      MakeField(&GravityPriorUse::error_deg,
                Info("error_deg")
                    .Json("error_deg")
                    .Unit("deg")
                    .Help("Angle between the prior and the localized pose's gravity")));
};

template <>
struct Description<PriorsUsed> {
  static constexpr std::string_view name = "PriorsUsed";
  static constexpr std::string_view help =
      "The query's priors as given (--prior-position, --prior-gravity, --priors, --use-exif-gps) "
      "and what they did";
  static constexpr auto fields =
      std::tuple(MakeField(&PriorsUsed::position, Info("position").Json("position")),
                 MakeField(&PriorsUsed::gravity, Info("gravity").Json("gravity")));
};

}  // namespace cwloc

#endif  // CWLOC_RESULTS_PRIORS_H_

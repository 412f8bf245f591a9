#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace sextant::engine {

/// The particle filter's own settings (type "pf": FastSLAM 2.0, estimators/filter/fastslam.hpp).
struct ParticleFilterConfig {
  int particles = 100;
  double resample_threshold = 0.5;  // low-variance resampling when N_eff < resample_threshold * particles
  uint64_t seed = 1;                // the random number generator's seed (deterministic replay)
  int confirmations = 3;            // sightings without id that make a tentative landmark permanent
  int tentative_lifetime = 50;      // sighting batches after which an unconfirmed one is dropped
};

/// Which online filter runs (config key `engine.filter.type`).
enum class FilterType {
  kEkf,   // "ekf": an EKF per body, planar or 3-D (filter_stage.hpp)
  kPf,    // "pf": FastSLAM 2.0 per odometry source, planar only (particle_filter_stage.hpp)
  kNone,  // "none": no filter stage
};
/// The kind of a config spelling; throws std::invalid_argument naming the spellings for any other name.
FilterType filter_type_from_name(const std::string& name);
const char* filter_type_name(FilterType type);

/// The online filter: a planar EKF per odometry source, fusing odometry increments and range-bearing landmark
/// sightings (localization against `map`, EKF-SLAM for landmarks not in it); or, with type "pf", FastSLAM 2.0 with
/// the same slam/gate/initial sigma/map settings and the `pf` ones.
struct FilterConfig {
  FilterType type = FilterType::kEkf;
  bool slam = true;                   // add landmarks that are not in `map` to the state
  double gate = 9.21;                 // chi-square threshold (2 dof) on the normalized innovation; 9.21 = 99 %
  double initial_sigma_xy = 0.01;     // m, first pose (the first odometry pose anchors the map frame)
  double initial_sigma_theta = 0.01;  // rad
  double min_increment_variance = 1e-10;
  int max_landmarks = 4096;
  double history_s = 0.5;  // late measurements up to this much older than the newest input are re-applied in order
  struct Landmark {
    int64_t id = 0;
    double x = 0, y = 0;
  };
  std::vector<Landmark> map;  // known landmarks (map frame)
  /// Odometry sources (odometry_t.source) and the body each belongs to (estimators/filter/multi_source_ekf.hpp):
  /// one filter per body; exactly one source of a body predicts, the others are fused as measurements.  A source
  /// not listed is a body of its own that predicts; a body without a predicting source gets the unlisted source of
  /// its own name as its predictor (so `vo: {body: robot1}` adds vo to robot1's own odometry).
  struct OdometrySource {
    std::string body;  // "" = the source's own name
    bool predict = false;
    std::array<bool, 6> fuse{true, true, true, false, false, false};  // x, y, yaw, vx, vy, vyaw
    bool differential = true;
    double gate = 0;       // chi-square threshold on the fused components; 0 = none
    double timeout_s = 0;  // 0 = never
  };
  std::map<std::string, OdometrySource> sources;
  ParticleFilterConfig pf;
};

}  // namespace sextant::engine

#pragma once
// FastSLAM 2.0 for a planar robot with range-bearing landmark sightings (Montemerlo, Thrun, Koller & Wegbreit,
// "FastSLAM 2.0: An improved particle filtering algorithm for simultaneous localization and mapping that provably
// converges", IJCAI 2003; Thrun, Burgard & Fox, Probabilistic Robotics, 2005, §13.4 and Table 13.2).  A
// Rao-Blackwellized particle filter (Doucet, de Freitas, Murphy & Russell, UAI 2000): each particle is a robot pose
// plus one 2x2 EKF per landmark, its map held in a copy-on-write tree (landmark_map_tree.hpp) so that resampling shares maps.
//
// Frames and units: poses s = (x, y, theta) of the body in the map frame (metres, radians, theta in (-pi, pi]);
// landmarks (x, y) in the map frame; a sighting z = (range [m], bearing [rad] from the body's x axis, counter-
// clockwise), with covariance R over (range, bearing); the sensor is at the body origin.  Models and Jacobians are
// the EKF's (PlanarEkf::motion, PlanarEkf::observation): s' = s (+) Delta with noise Q on the right of Delta, and
// h(s, l) = (|l - p|, atan2(l - p) - theta).
//
// Motion between sightings is not sampled step by step: each particle carries the Gaussian of its motion since it
// was last sampled, N(s_hat, P) (s_hat = composed odometry increments, P = F P F' + G Q G' per increment).  At a
// batch of sightings (one image), in the paper's notation with z_hat = h(s_hat, mu_n), G_s = dh/ds, G_theta = dh/dl:
//   - Improved proposal: for each sighting in turn, Q_n = R + G_theta Sigma_n G_theta', and the pose Gaussian is
//       Sigma_s = [G_s' Q_n^-1 G_s + P^-1]^-1,   mu_s = s_hat + Sigma_s G_s' Q_n^-1 (z - z_hat),
//     computed in the equivalent gain form K = P G_s' (G_s P G_s' + Q_n)^-1, mu_s = s_hat + K (z - z_hat),
//     Sigma_s = (I - K G_s) P (I - K G_s)' + K Q_n K' (valid for a singular P); the next sighting of the batch
//     starts from (mu_s, Sigma_s).  Then s ~ N(mu_s, Sigma_s).
//   - Importance weight: w *= N(z - z_hat; 0, L), L = G_s P G_s' + G_theta Sigma_n G_theta' + R (per sighting,
//     with the P the sighting saw: the product is p(z_1..z_k | past, map) of the particle).
//   - Landmark update with the sampled pose: the standard EKF, K = Sigma_n H' (H Sigma_n H' + R)^-1,
//     mu_n += K (z - h(s, mu_n)), Sigma_n Joseph form; a new landmark is initialized by inverting h at s,
//     mu = p + r (cos(theta + b), sin(theta + b)), Sigma = J_z R J_z'.
//   - Resampling: low-variance, when N_eff = 1 / sum w^2 < resample_threshold * N (low_variance_resampling.hpp).
// Landmarks:
//   - id >= 0 in the known map (set_known_landmark): fixed, Sigma_n = 0 (localization);
//   - other ids >= 0 (SLAM mode): created in every particle at their first sighting, then updated;
//   - id < 0: per-particle maximum-likelihood association over the known map and the particle's landmarks:
//     the candidate of largest N(z - z_hat; 0, L) among those with Mahalanobis distance d2 = nu' L^-1 nu below
//     `gate` (each landmark used once per image); none: a new tentative landmark, weighted by the likelihood of a
//     sighting at the gate, exp(-gate / 2) / (2 pi sqrt|R|) (the "new landmark" probability p0), provided d2
//     exceeds `new_landmark_gate` for every candidate (between the two gates the sighting is ambiguous: weighted
//     by p0, used for nothing; otherwise the 1 % of true sightings beyond the gate would seed duplicates).  A tentative
//     landmark that is not seen `confirmations` times within `tentative_lifetime` images is removed, so a
//     spurious sighting does not stay in the map.
// Bounded work: the association of sightings without id costs particles x landmarks per sighting.  A batch takes
// only as many of them (in their order) as `association_budget` candidate evaluations allow; the others are dropped
// before any particle sees them (the same in every particle, so the weights stay comparable) and counted as
// `over_budget`.  Sightings with ids cost one evaluation each and are never dropped.
// Outliers: a sighting whose d2 exceeds `gate` in a particle does not update that particle, whose weight is
// multiplied by the same p0 (a robust likelihood); a sighting gated in every particle is counted as gated.
// Bad input (non-finite numbers, non-positive range, covariances that are not symmetric positive definite) is
// counted and refused; it never changes the particles.  Deterministic for a seed (std::mt19937_64).
#include "estimators/filter/estimate_health.hpp"
#include "estimators/filter/landmark_map_tree.hpp"
#include "estimators/lie/se2.hpp"

#include <cstdint>
#include <map>
#include <optional>
#include <random>
#include <unordered_map>
#include <vector>

namespace sextant::filter {

struct FastSlamOptions {
  int particles = 100;
  double resample_threshold = 0.5;  // resample when N_eff < resample_threshold * particles
  uint64_t seed = 1;
  bool slam = true;                        // false: only the known map is used (localization)
  double gate = 9.21;                      // chi-square (2 dof) on d2 = nu' L^-1 nu; 9.21 = 99 %
  double new_landmark_gate = 18.42;        // a sighting without id makes a new landmark only beyond this d2 (99.99 %)
  int max_landmarks = 4096;                // per particle
  int confirmations = 3;                   // sightings that make a landmark without id permanent
  int tentative_lifetime = 50;             // images after which an unconfirmed landmark without id is dropped
  int64_t association_budget = 2'000'000;  // candidate evaluations per batch for sightings without id (~0.2 s)
};

/// One range-bearing sighting; id < 0 when the landmark is not identified.
struct RangeBearing {
  int64_t id = -1;
  double range = 0, bearing = 0;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
};

/// What happened to one batch of sightings (counted in the particle of largest weight before the batch, except
/// `gated`, `rejected` and `unknown`, which are the same for every particle).
struct FastSlamBatchOutcome {
  int updated = 0;      // identified sightings that updated a landmark (or the pose, for a known landmark)
  int created = 0;      // new landmarks (identified, or tentative without id)
  int associated = 0;   // sightings without id paired with a landmark
  int gated = 0;        // outside the gate in every particle
  int rejected = 0;     // bad input
  int unknown = 0;      // id not in the known map in localization mode, or the map is full
  int removed = 0;      // tentative landmarks dropped
  int over_budget = 0;  // sightings without id dropped: their association would exceed association_budget
  bool resampled = false;
  double effective_sample_size = 0;  // before resampling
};

/// A Gaussian over the pose (x, y, theta).
struct PoseGaussian {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};

class FastSlam {
 public:
  struct Particle {
    PoseGaussian pose;  // mean s_hat; covariance P of the motion not yet sampled (0 right after sampling)
    double log_weight = 0;
    LandmarkMapTree identified;    // slots from the filter's id table (same slot for an id in every particle)
    LandmarkMapTree unidentified;  // this particle's landmarks created from sightings without id
  };

  explicit FastSlam(const FastSlamOptions& options = {});

  /// All particles at `pose` with the unsampled covariance `covariance`; empties the maps (not the known map).
  void initialize(const SE2& pose, const Eigen::Matrix3d& covariance);
  bool initialized() const { return initialized_; }
  void set_known_landmark(int64_t id, const Eigen::Vector2d& position) { known_[id] = position; }

  /// Odometry increment Delta with covariance Q (3x3 over [dx, dy, dtheta], body frame after the motion).
  /// Returns false (and changes nothing) for non-finite input or a Q that is not positive semi-definite.
  bool predict(const SE2& delta, const Eigen::Matrix3d& Q);

  /// One batch of simultaneous sightings (one image).
  FastSlamBatchOutcome observe(const std::vector<RangeBearing>& sightings);

  /// Weighted mean pose (circular mean for theta) and the covariance of the particle mixture:
  /// sum_i w_i (d_i d_i' + P_i), d_i = s_hat_i - mean (theta difference wrapped).  Map-frame (x, y, theta).
  SE2 mean_pose() const;
  Eigen::Matrix3d pose_covariance() const;
  /// Both at once (one pass over the weights); either pointer may be null.
  void mixture(SE2* mean, Eigen::Matrix3d* covariance) const;

  const std::vector<Particle>& particles() const { return particles_; }
  /// Whether the filter's estimate may be kept (estimate_health.hpp): every particle's pose and weight finite, its
  /// pose covariance with no negative variance, and the mixture's covariance positive semi-definite.  O(particles);
  /// the landmark maps are not walked (their updates refuse a non-positive innovation covariance).
  Health health() const;
  std::vector<double> weights() const;
  double effective_sample_size() const;
  int resamplings() const { return resamplings_; }
  /// Landmarks of the particle of largest weight (known map, identified, and confirmed landmarks without id,
  /// the latter with ids from 2^40 + slot).
  std::map<int64_t, Eigen::Vector2d> landmarks() const;

  /// One step of the improved proposal (header, first bullet) for landmark (mu_n, Sigma_n): updates `pose` in
  /// place and returns log N(z - z_hat; 0, L) and d2, or nullopt when the geometry is degenerate or L is not
  /// positive definite.  Exposed for tests.
  struct ProposalStep {
    double log_likelihood = 0, d2 = 0;
  };
  static std::optional<ProposalStep> refine_proposal(PoseGaussian& pose, const Eigen::Vector2d& landmark_mean,
                                                     const Eigen::Matrix2d& landmark_covariance,
                                                     const Eigen::Vector2d& z, const Eigen::Matrix2d& R);
  /// Low-variance resampling of the particles by their weights (shares the maps); exposed for tests.
  void resample();

  /// The filter's state (particles with their maps, the id table, the random generator's state, counters) in the
  /// binary archive; a loaded filter draws the same numbers as the saved one would.  The options are the
  /// constructor's.
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);

 private:
  struct Pending;
  struct Proposal;
  bool valid(const RangeBearing& s) const;
  void drop_over_budget(std::vector<RangeBearing>& batch, std::vector<int>& slot, FastSlamBatchOutcome& out) const;
  void observe_particle(Particle& p, const std::vector<RangeBearing>& batch, const std::vector<int>& identified_slot,
                        std::vector<char>& gated_here, FastSlamBatchOutcome* stats);
  // observe_particle's steps (fastslam.cpp).
  void propose_with_id(Proposal& q, const Particle& p, const RangeBearing& s, size_t j, int slot,
                       std::vector<char>& gated_here, FastSlamBatchOutcome* stats) const;
  void propose_without_id(Proposal& q, const Particle& p, const RangeBearing& s, size_t j, int identified_count,
                          FastSlamBatchOutcome* stats) const;
  void update_particle_map(Particle& p, const std::vector<RangeBearing>& batch,
                           const std::vector<Pending>& pending) const;
  void drop_stale_tentatives(Particle& p, FastSlamBatchOutcome* stats) const;
  Eigen::Vector3d sample(const PoseGaussian& g);

  FastSlamOptions options_;
  bool initialized_ = false;
  std::vector<Particle> particles_;
  std::map<int64_t, Eigen::Vector2d> known_;
  std::unordered_map<int64_t, int32_t> identified_slot_;  // id -> slot in Particle::identified
  int64_t batches_ = 0;
  int resamplings_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace sextant::filter

#pragma once
// A planar extended Kalman filter for a robot with range-bearing landmark observations: localization against a
// known map, and EKF-SLAM (state augmentation) for landmarks not in the map (Thrun,
// Burgard & Fox, Probabilistic Robotics, ch. 10).
// State: [x, y, theta, l1x, l1y, l2x, l2y, ...] in the map frame; P its covariance in that parameterization.
//  - Motion: x' = x (+) Delta with Delta an SE(2) odometry increment whose noise Q (3x3, [dx dy dtheta]) is given
//    on the right of Delta (in the body frame after the motion):  F = d x'/d x,  G = d x'/d w = blockdiag(R(theta'), 1).
//  - Observation of landmark l from the robot origin: h = [|l - p|, atan2(ly - py, lx - px) - theta], the bearing
//    innovation wrapped to (-pi, pi].
//  - Pose measurements (other odometry sources, estimators/filter/multi_source_ekf.hpp): a pose Z = h(x) * Exp(v),
//    v ~ N(0, R) on the right, either of the robot pose in another frame, h = F^-1 X (absolute), or of its motion
//    since a clone of an earlier pose, h = C^-1 X (relative; the clone is a copy of the robot pose kept in the
//    state, "stochastic cloning", Roumeliotis & Burdick, ICRA 2002).  Innovation r = Log(h^-1 Z), on any subset
//    of its [x, y, theta] rows.
#include "assoc/landmark/jcbb.hpp"
#include "estimators/archive/binary_archive.hpp"
#include "estimators/filter/estimate_health.hpp"
#include "estimators/filter/kalman_update.hpp"
#include "estimators/lie/se2.hpp"

#include <array>
#include <map>

namespace sextant::filter {

struct PlanarEkfOptions {
  double gate = 9.21;  // chi-square (2 dof) threshold on the normalized innovation; 9.21 = 99 %
  bool slam = true;    // unknown landmark ids are added to the state; false: only the known map is used
  int max_landmarks = 4096;
  // Sightings without an id: a sighting that JCBB pairs with no landmark becomes a tentative landmark (outside the
  // state); it joins the map after `confirmations` sightings within `tentative_radius` metres, and is forgotten
  // after `tentative_lifetime` batches without one, so a spurious sighting never becomes a permanent landmark.
  int confirmations = 3;
  double tentative_radius = 0.5;
  int tentative_lifetime = 50;
  // The work one batch of sightings without id may cost in association (assoc/landmark/jcbb.hpp, in floating-point
  // operations; 5e7 is about 50 ms).  Beyond it the association degrades to nearest neighbour, and sightings it
  // could not examine are dropped (counted as over_budget).
  double association_budget = 5e7;
  // The work the updates of one batch of sightings may cost (kalman_update.hpp, UpdateBudget): each EKF-SLAM update
  // or new landmark is O(n^2) in the state's size n; what does not fit is dropped and counted as over_budget.
  // 5e8 is about 0.3 s: with 500 landmarks, about 60 sightings a batch.
  double update_budget = 5e8;
};

/// A range-bearing sighting of a landmark whose id is unknown.
struct Sighting {
  double range = 0, bearing = 0;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
};

/// What happened to a batch of unidentified sightings.
struct AssociationOutcome {
  int paired = 0, gated = 0, tentative = 0, confirmed = 0;
  int over_budget = 0;     // sightings dropped unexamined (budget) or beyond the tentative list's size (max_landmarks)
  bool exhausted = false;  // the association budget ran out: nearest neighbour instead of JCBB
};

class PlanarEkf {
 public:
  explicit PlanarEkf(const PlanarEkfOptions& options = {}) : options_(options) {}

  void initialize(const SE2& pose, const Eigen::Matrix3d& covariance);
  bool initialized() const { return initialized_; }
  /// A landmark of the known map: fixed, not part of the state.
  void set_known_landmark(int64_t id, const Eigen::Vector2d& position) { known_[id] = position; }

  /// The motion model above.  A prediction whose result is not finite, or whose robot covariance is not positive
  /// semi-definite (estimate_health.hpp), is refused: the state stays as it was, the refusal is counted and returned.
  Health predict(const SE2& delta, const Eigen::Matrix3d& Q);
  /// One range-bearing sighting of landmark `id` (covariance R over [range, bearing]).  A known landmark updates;
  /// a landmark in the state updates; a new one is added (SLAM mode).  Refused when gated or degenerate.
  UpdateResult observe(int64_t id, double range, double bearing, const Eigen::Matrix2d& R);

  /// Adds a copy of the current robot pose to the state, fully correlated with it (stochastic cloning); returns
  /// its index in the state.  `refresh_clone` sets an existing clone to the current pose again.
  int add_pose_clone();
  void refresh_clone(int index);
  /// Z = C^-1 X Exp(v): the motion since the clone at `clone_index`, measured with covariance R over
  /// [dx, dy, dtheta] (right perturbation, body frame); only the rows with `rows[i]` true are fused.
  UpdateResult observe_relative_pose(int clone_index, const SE2& z, const Eigen::Matrix3d& R,
                                     const std::array<bool, 3>& rows, double gate);
  /// Z = F^-1 X Exp(v): the robot pose in the frame F.
  UpdateResult observe_pose(const SE2& frame, const SE2& z, const Eigen::Matrix3d& R, const std::array<bool, 3>& rows,
                            double gate);

  /// Sightings without ids: associated by JCBB (assoc/landmark/jcbb.hpp) against every landmark of the map and
  /// the state, then updated jointly; the unpaired ones go through the tentative-landmark rule above.
  /// Each update or new landmark is charged to `budget`; those that do not fit count as over_budget.
  AssociationOutcome observe_unidentified(const std::vector<Sighting>& sightings, UpdateBudget& budget);
  AssociationOutcome observe_unidentified(const std::vector<Sighting>& sightings) {
    UpdateBudget budget = new_update_budget();
    return observe_unidentified(sightings, budget);
  }
  /// A batch's budget (the options' update_budget).
  UpdateBudget new_update_budget() const { return UpdateBudget(options_.update_budget); }

  SE2 pose() const { return SE2(x_[0], x_[1], x_[2]); }
  Eigen::Matrix3d pose_covariance() const { return P_.topLeftCorner<3, 3>(); }
  const Eigen::VectorXd& state() const { return x_; }
  const Eigen::MatrixXd& covariance() const { return P_; }
  std::map<int64_t, Eigen::Vector2d> landmarks() const;
  size_t landmark_count() const { return slot_.size(); }
  /// Predictions and updates refused because of what they would have done to the estimate (every update, landmark
  /// addition and prediction is checked; the state is the one before the refused step).
  const Refusals& refusals() const { return refusals_; }

  /// The models and their Jacobians, exposed for tests.
  static Eigen::Vector3d motion(const Eigen::Vector3d& x, const SE2& delta, Eigen::Matrix3d* F, Eigen::Matrix3d* G);
  static Eigen::Vector2d observation(const Eigen::Vector3d& robot, const Eigen::Vector2d& landmark,
                                     Eigen::Matrix<double, 2, 3>* H_robot, Eigen::Matrix2d* H_landmark);
  /// The innovation r = Log((C^-1 X)^-1 Z) of a relative pose measurement, for the clone C and the robot X given
  /// as [x, y, theta]; H_clone = -dr/dC and H_robot = -dr/dX (so that r(x + dx) ~ r - H dx, the EKF convention).
  static Eigen::Vector3d relative_pose_innovation(const Eigen::Vector3d& clone, const Eigen::Vector3d& robot,
                                                  const SE2& z, Eigen::Matrix3d* H_clone, Eigen::Matrix3d* H_robot);
  /// The innovation of an absolute pose measurement Z of F^-1 X, with H_robot = -dr/dX.
  static Eigen::Vector3d pose_innovation(const SE2& frame, const Eigen::Vector3d& robot, const SE2& z,
                                         Eigen::Matrix3d* H_robot);

  /// The filter's state (estimate, covariance, landmarks) in the binary archive (the daemon's state directory); the
  /// options are the constructor's.
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);

 private:
  // observe_unidentified's steps: the landmarks as an index, their association, the unpaired sightings' tentative
  // landmarks.
  std::vector<std::pair<int64_t, bool>> association_index() const;
  assoc::BoundedAssociation associate(const std::vector<Sighting>& sightings,
                                      const std::vector<std::pair<int64_t, bool>>& ids) const;
  void admit_tentative(const std::vector<Sighting>& sightings, const std::vector<size_t>& unpaired,
                       UpdateBudget& budget, AssociationOutcome& out);
  Health augment(int64_t id, double range, double bearing, const Eigen::Matrix2d& R);
  UpdateResult counted(UpdateResult r);
  UpdateResult update_rows(const Eigen::Vector3d& r, const Eigen::Matrix3d& H_robot, int other,
                           const Eigen::Matrix3d& H_other, const Eigen::Matrix3d& R, const std::array<bool, 3>& rows,
                           double gate);

  PlanarEkfOptions options_;
  bool initialized_ = false;
  Eigen::VectorXd x_ = Eigen::VectorXd::Zero(3);
  Eigen::MatrixXd P_ = Eigen::MatrixXd::Identity(3, 3);
  std::map<int64_t, Eigen::Vector2d> known_;
  std::map<int64_t, int> slot_;  // landmark id -> index of its x in the state
  struct Tentative {
    Eigen::Vector2d position;
    int seen = 1, idle = 0;
    Sighting last;
  };
  std::vector<Tentative> tentative_;
  int64_t next_id_ = int64_t{1} << 40;  // ids given to confirmed landmarks that came without one
  Refusals refusals_;
};

}  // namespace sextant::filter

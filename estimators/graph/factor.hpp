#pragma once
// Factors: residuals e(x) of a few variables with an information matrix Omega; the graph minimizes
// chi2 = sum over factors of e' Omega e (g2o's convention: no 1/2).
#include "estimators/graph/variable.hpp"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace sextant::graph {

/// A factor's residual and its Jacobians with respect to the right-perturbed variables, in reusable buffers.
struct Linearization {
  Eigen::VectorXd error;
  std::vector<Eigen::MatrixXd> jacobians;  // one per variable, residual_dim x variable dim
};

class Factor {
 public:
  Factor(std::vector<int> variables, Eigen::MatrixXd information)
      : variables_(std::move(variables)), information_(std::move(information)) {}
  virtual ~Factor() = default;

  /// Indices into FactorGraph::variables().
  const std::vector<int>& variables() const { return variables_; }
  const Eigen::MatrixXd& information() const { return information_; }
  int residual_dim() const { return static_cast<int>(information_.rows()); }
  /// A short name for messages ("EDGE_SE2", "prior", ...).
  virtual std::string type() const = 0;
  /// True for a factor that ties its variables to the map frame itself (a prior), not only to each other: with one,
  /// chi2 changes when the whole map moves, so the problem has no gauge freedom left to fix.
  virtual bool fixes_gauge() const { return false; }

  /// The residual only (for chi2).
  virtual void error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const = 0;
  /// Residual and Jacobians; `out` is sized by the caller (see make_linearization).
  virtual void linearize(const std::vector<Variable>& vars, Linearization& out) const = 0;

  Linearization make_linearization(const std::vector<Variable>& vars) const;
  /// Gives `l` this factor's shape (the residual's size, one Jacobian per variable of its size), keeping the buffers
  /// it already has when the shape is the same: linearizing many factors into one Linearization then allocates only
  /// when the shape changes.
  void shape(Linearization& l, const std::vector<Variable>& vars) const;
  double chi2(const std::vector<Variable>& vars) const;
  /// The same with the caller's scratch vectors (no allocation once they have the residual's size); `e` is left
  /// holding the residual.
  double chi2(const std::vector<Variable>& vars, Eigen::VectorXd& e, Eigen::VectorXd& weighted) const;
  /// e' Omega e for a residual `e` of this factor, `weighted` a scratch vector.
  double weighted_square(const Eigen::VectorXd& e, Eigen::VectorXd& weighted) const {
    weighted.noalias() = information_ * e;
    return e.dot(weighted);
  }

  /// A copy of this factor.
  virtual std::unique_ptr<Factor> clone() const = 0;
  /// The same factor on other variable indices (for feeding a graph's factors to another graph).
  std::unique_ptr<Factor> rebind(std::vector<int> variables) const {
    auto f = clone();
    f->variables_ = std::move(variables);
    return f;
  }

 private:
  std::vector<int> variables_;
  Eigen::MatrixXd information_;
};

/// The relative pose Z between poses i and j, with g2o's residual (EDGE_SE2 and EDGE_SE3:QUAT):
/// E = Z^-1 (Xi^-1 Xj);  2-D: e = [t_E; wrap(theta_E)];  3-D: e = [t_E; vec(q_E)] with q_E normalized, w >= 0.
/// Jacobians: J_j = blockdiag(R_E, dq) and J_i = -J_j Ad(D^-1), D = Xi^-1 Xj, where dq = 1 (2-D) or
/// 1/2 (w I + [v]x) for q_E = (w, v) (3-D), the derivative of vec(q_E Exp(phi)) at phi = 0.
class RelativePoseFactor final : public Factor {
 public:
  std::unique_ptr<Factor> clone() const override { return std::make_unique<RelativePoseFactor>(*this); }
  RelativePoseFactor(int i, int j, const SE2& z, Eigen::Matrix3d information);
  RelativePoseFactor(int i, int j, const SE3& z, Matrix6d information);
  std::string type() const override { return planar_ ? "EDGE_SE2" : "EDGE_SE3:QUAT"; }
  void error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const override;
  void linearize(const std::vector<Variable>& vars, Linearization& out) const override;
  bool planar() const { return planar_; }
  const SE2& measurement2() const { return z2_; }
  const SE3& measurement3() const { return z3_; }

 private:
  bool planar_;
  SE2 z2_;
  SE3 z3_;
};

/// A prior Z on one pose, with the same residual as RelativePoseFactor (E = Z^-1 X).
class PosePriorFactor final : public Factor {
 public:
  std::unique_ptr<Factor> clone() const override { return std::make_unique<PosePriorFactor>(*this); }
  PosePriorFactor(int i, const SE2& z, Eigen::Matrix3d information);
  PosePriorFactor(int i, const SE3& z, Matrix6d information);
  std::string type() const override { return "prior"; }
  bool fixes_gauge() const override { return true; }
  void error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const override;
  void linearize(const std::vector<Variable>& vars, Linearization& out) const override;

 private:
  bool planar_;
  SE2 z2_;
  SE3 z3_;
};

/// A pose observing a point: l = (X S)^-1 p is the point in the sensor frame (S: the sensor's pose on the body),
/// and the measurement model h(l) is one of:
///   kPosition    l itself (EDGE_SE2_XY, EDGE_SE3_TRACKXYZ)
///   kRangeBearing   [|l|, atan2(ly, lx)]                          (2-D)
///   kRangeAzimuthElevation [|l|, atan2(ly, lx), atan2(lz, |lxy|)] (3-D)
///   kBearing     atan2(ly, lx) (2-D) or [azimuth, elevation] (3-D): bearing-only
/// e = h(l) - z, angle components wrapped to (-pi, pi].
class PointObservationFactor final : public Factor {
 public:
  std::unique_ptr<Factor> clone() const override { return std::make_unique<PointObservationFactor>(*this); }
  enum class Model { kPosition, kRangeBearing, kRangeAzimuthElevation, kBearing };
  PointObservationFactor(int pose, int point, Model model, Eigen::VectorXd z, Eigen::MatrixXd information,
                         SE3 sensor_offset = SE3());
  std::string type() const override;
  void error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const override;
  void linearize(const std::vector<Variable>& vars, Linearization& out) const override;
  Model model() const { return model_; }
  const Eigen::VectorXd& measurement() const { return z_; }
  /// The sensor's pose in the body frame (g2o's PARAMS_SE3OFFSET; the identity by default).
  const SE3& sensor_offset() const { return offset_; }

 private:
  void evaluate(const std::vector<Variable>& vars, Eigen::VectorXd& e, Linearization* out) const;
  Model model_;
  Eigen::VectorXd z_;
  SE3 offset_;
  SE2 offset2_;  // offset_'s planar part, for planar poses
};

/// A pose observing a point fixed on another pose: one robot's sighting of another robot's marker.  The observed
/// point is p = Y m (Y the observed pose, m the marker's position in Y's frame, metres) and the residual that of
/// PointObservationFactor on (X, p); the Jacobian with respect to Y's right perturbation is J_p dp/dY with
/// dp/dY = R_Y [I  -[m]x] (3-D) or R_Y [I  (-m_y, m_x)'] (planar).
class PoseObservationFactor final : public Factor {
 public:
  std::unique_ptr<Factor> clone() const override { return std::make_unique<PoseObservationFactor>(*this); }
  PoseObservationFactor(int observer, int observed, PointObservationFactor::Model model, Eigen::VectorXd z,
                        Eigen::MatrixXd information, SE3 sensor_offset, Eigen::Vector3d marker);
  std::string type() const override { return "POSE_OBSERVATION"; }
  void error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const override;
  void linearize(const std::vector<Variable>& vars, Linearization& out) const override;
  PointObservationFactor::Model model() const { return point_.model(); }
  const Eigen::VectorXd& measurement() const { return point_.measurement(); }
  const SE3& sensor_offset() const { return point_.sensor_offset(); }
  const Eigen::Vector3d& marker() const { return marker_; }

 private:
  /// The observer and the observed point as the variables of point_ (indices 0 and 1).
  std::vector<Variable> observer_and_point(const std::vector<Variable>& vars) const;
  PointObservationFactor point_;  // on variables {0, 1} of observer_and_point
  Eigen::Vector3d marker_;
};

}  // namespace sextant::graph

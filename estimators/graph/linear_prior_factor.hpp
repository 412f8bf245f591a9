#pragma once
// A quadratic cost on several variables, linear in their offsets from fixed values x0 in the tangent space:
//   e = r0 + J d,  d = [x_1 (-) x0_1; ...; x_n (-) x0_n],  Omega = I,
// where x (-) x0 = Log(X0^-1 X) for a pose (the tangent of the right perturbation taking X0 to X) and x - x0 for a
// point or vector.  It is what marginalizing variables out of a linearized problem leaves on the variables they
// shared factors with (the Schur complement; Sibley, Matthies and Sukhatme, "Sliding window filter with application
// to planetary landing", JFR 2010), and also a Gaussian prior on several variables at once (r0 = 0).
// The Jacobian with respect to variable k's right perturbation is J_k Jr^-1(x_k (-) x0_k) for a pose, J_k otherwise.
#include "estimators/graph/factor.hpp"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace sextant::graph {

class LinearPriorFactor final : public Factor {
 public:
  /// The cost 2 b'd + d'H d (g2o's chi2 convention, H = sum J'Omega J and b = sum J'Omega e of the factors it
  /// replaces) up to a constant, about x0 (one Variable per index in `variables`, in order; d ordered likewise):
  /// J = S^1/2 U', r0 = S^-1/2 U' b with H = U S U', the eigen-directions with S below rank_tolerance * max(S)
  /// dropped (unobservable directions carry no information).  Throws std::invalid_argument when H or b does not
  /// match the variables' dimensions, is not finite, or H has no positive eigenvalue.
  static std::unique_ptr<LinearPriorFactor> from_hessian(std::vector<int> variables, std::vector<Variable> x0,
                                                         const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                                                         double rank_tolerance = 1e-12);
  /// A Gaussian prior: the variables at mean x0 with the given information (on the stacked d).
  static std::unique_ptr<LinearPriorFactor> gaussian(std::vector<int> variables, std::vector<Variable> x0,
                                                     const Eigen::MatrixXd& information);

  std::unique_ptr<Factor> clone() const override { return std::make_unique<LinearPriorFactor>(*this); }
  std::string type() const override { return "LINEAR_PRIOR"; }
  bool fixes_gauge() const override { return true; }
  void error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const override;
  void linearize(const std::vector<Variable>& vars, Linearization& out) const override;

  LinearPriorFactor(std::vector<int> variables, std::vector<Variable> x0, Eigen::MatrixXd J, Eigen::VectorXd r0);

 private:
  /// d for the current values, and the per-variable Jr^-1 (identity for points and vectors) when asked.
  Eigen::VectorXd offset(const std::vector<Variable>& vars, std::vector<Eigen::MatrixXd>* jr_inv) const;
  std::vector<Variable> x0_;
  Eigen::MatrixXd J_;
  Eigen::VectorXd r0_;
};

/// The information the factors leave on their variables other than `eliminate` (indices into vars) once those are
/// marginalized, linearized at the current values: with H = sum J'Omega J and b = sum J'Omega e stacked over
/// [eliminated; kept] (kept: the factors' other variables, in order of first appearance),
///   H* = H_kk - H_ke H_ee^-1 H_ek,  b* = b_k - H_ke H_ee^-1 b_e   (the Schur complement).
/// Throws std::invalid_argument when H_ee is singular (an eliminated variable its factors do not determine).
struct MarginalInformation {
  std::vector<int> kept;
  Eigen::MatrixXd H;  // over the kept variables' stacked tangents, in the order of `kept`
  Eigen::VectorXd b;
};
MarginalInformation marginal_information(const std::vector<Variable>& vars, const std::vector<const Factor*>& factors,
                                         const std::vector<int>& eliminate);

/// Marginalizes `eliminate` out of `factors` (every factor touching them, possibly others): the LinearPriorFactor of
/// marginal_information on the kept variables at their current values, or nullptr when nothing is kept.
std::unique_ptr<LinearPriorFactor> marginalize(const std::vector<Variable>& vars,
                                               const std::vector<const Factor*>& factors,
                                               const std::vector<int>& eliminate);

/// x (-) x0 for two variables of the same kind (see the file comment), with Jr^-1 of the result for poses (the
/// identity for points and vectors) when asked.
Eigen::VectorXd tangent_offset(const Variable& x, const Variable& x0, Eigen::MatrixXd* jr_inv = nullptr);

}  // namespace sextant::graph

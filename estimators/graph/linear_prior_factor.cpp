#include "estimators/graph/linear_prior_factor.hpp"

#include "estimators/spd_matrix.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>

#include <cmath>
#include <stdexcept>

namespace sextant::graph {

Eigen::VectorXd tangent_offset(const Variable& x, const Variable& x0, Eigen::MatrixXd* jr_inv) {
  if (x.kind != x0.kind) throw std::invalid_argument("tangent_offset: variables of different kinds");
  switch (x.kind) {
    case VariableKind::kPose2: {
      Eigen::Matrix3d Ji;
      const Eigen::Vector3d d = (x0.pose2.inverse() * x.pose2).log(&Ji);
      if (jr_inv) *jr_inv = Ji;
      return d;
    }
    case VariableKind::kPose3: {
      Matrix6d Ji;
      const Vector6d d = (x0.pose3.inverse() * x.pose3).log(&Ji);
      if (jr_inv) *jr_inv = Ji;
      return d;
    }
    case VariableKind::kPoint2:
      if (jr_inv) *jr_inv = Eigen::Matrix2d::Identity();
      return (x.point - x0.point).head<2>();
    case VariableKind::kPoint3:
    case VariableKind::kVector3:
      if (jr_inv) *jr_inv = Eigen::Matrix3d::Identity();
      return x.point - x0.point;
  }
  return {};
}

LinearPriorFactor::LinearPriorFactor(std::vector<int> variables, std::vector<Variable> x0, Eigen::MatrixXd J,
                                     Eigen::VectorXd r0)
    : Factor(std::move(variables), Eigen::MatrixXd::Identity(J.rows(), J.rows())),
      x0_(std::move(x0)),
      J_(std::move(J)),
      r0_(std::move(r0)) {
  int n = 0;
  for (const auto& v : x0_) n += v.dim();
  if (x0_.size() != this->variables().size() || J_.cols() != n || r0_.size() != J_.rows() || J_.rows() == 0)
    throw std::invalid_argument("LinearPriorFactor: J, r0 and the variables' dimensions do not match");
  if (!J_.allFinite() || !r0_.allFinite()) throw std::invalid_argument("LinearPriorFactor: non-finite J or r0");
}

std::unique_ptr<LinearPriorFactor> LinearPriorFactor::from_hessian(std::vector<int> variables, std::vector<Variable> x0,
                                                                   const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                                                                   double rank_tolerance) {
  if (H.rows() != H.cols() || b.size() != H.rows() || !H.allFinite() || !b.allFinite())
    throw std::invalid_argument("LinearPriorFactor: H and b must be finite, square and of one size");
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(symmetrized(H));
  const Eigen::VectorXd& s = eig.eigenvalues();
  const double top = s.size() ? s.maxCoeff() : 0;
  if (!(top > 0)) throw std::invalid_argument("LinearPriorFactor: H has no positive eigenvalue");
  std::vector<int> kept;
  for (int k = 0; k < s.size(); ++k)
    if (s[k] > rank_tolerance * top) kept.push_back(k);
  Eigen::MatrixXd J(static_cast<int>(kept.size()), H.cols());
  Eigen::VectorXd r0(static_cast<int>(kept.size()));
  for (size_t r = 0; r < kept.size(); ++r) {
    const int k = kept[r];
    const double root = std::sqrt(s[k]);
    J.row(static_cast<int>(r)) = root * eig.eigenvectors().col(k).transpose();
    r0[static_cast<int>(r)] = eig.eigenvectors().col(k).dot(b) / root;
  }
  return std::make_unique<LinearPriorFactor>(std::move(variables), std::move(x0), std::move(J), std::move(r0));
}

std::unique_ptr<LinearPriorFactor> LinearPriorFactor::gaussian(std::vector<int> variables, std::vector<Variable> x0,
                                                               const Eigen::MatrixXd& information) {
  if (!is_positive_definite(information))
    throw std::invalid_argument("LinearPriorFactor: the prior's information is not positive definite");
  return from_hessian(std::move(variables), std::move(x0), information, Eigen::VectorXd::Zero(information.rows()));
}

Eigen::VectorXd LinearPriorFactor::offset(const std::vector<Variable>& vars,
                                          std::vector<Eigen::MatrixXd>* jr_inv) const {
  Eigen::VectorXd d(J_.cols());
  int at = 0;
  for (size_t k = 0; k < x0_.size(); ++k) {
    const Variable& x = vars[static_cast<size_t>(variables()[k])];
    const Eigen::VectorXd dk = tangent_offset(x, x0_[k], jr_inv ? &(*jr_inv)[k] : nullptr);
    d.segment(at, dk.size()) = dk;
    at += static_cast<int>(dk.size());
  }
  return d;
}

void LinearPriorFactor::error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const {
  e = r0_ + J_ * offset(vars, nullptr);
}

void LinearPriorFactor::linearize(const std::vector<Variable>& vars, Linearization& out) const {
  std::vector<Eigen::MatrixXd> jr_inv(x0_.size());
  out.error = r0_ + J_ * offset(vars, &jr_inv);
  int at = 0;
  for (size_t k = 0; k < x0_.size(); ++k) {
    const int n = x0_[k].dim();
    out.jacobians[k] = J_.middleCols(at, n) * jr_inv[k];
    at += n;
  }
}

namespace {

// Columns of each variable in the stacked system: eliminated first, then the kept ones in order of appearance.
struct Columns {
  std::vector<int> order;         // variable indices
  std::vector<int> start;         // per entry of order
  int eliminated = 0, total = 0;  // scalar columns
  size_t eliminated_variables = 0;
  int of(int variable) const {
    const auto it = std::find(order.begin(), order.end(), variable);
    return start[static_cast<size_t>(it - order.begin())];
  }
};

Columns stack_columns(const std::vector<Variable>& vars, const std::vector<const Factor*>& factors,
                      const std::vector<int>& eliminate) {
  Columns c;
  auto add = [&](int v) {
    if (std::find(c.order.begin(), c.order.end(), v) != c.order.end()) return;
    c.order.push_back(v);
    c.start.push_back(c.total);
    c.total += vars[static_cast<size_t>(v)].dim();
  };
  for (int v : eliminate) add(v);
  c.eliminated = c.total;
  c.eliminated_variables = c.order.size();
  for (const Factor* f : factors)
    for (int v : f->variables()) add(v);
  return c;
}

}  // namespace

MarginalInformation marginal_information(const std::vector<Variable>& vars, const std::vector<const Factor*>& factors,
                                         const std::vector<int>& eliminate) {
  const Columns c = stack_columns(vars, factors, eliminate);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(c.total, c.total);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(c.total);
  for (const Factor* f : factors) {
    Linearization l = f->make_linearization(vars);
    f->linearize(vars, l);
    const auto& fv = f->variables();
    for (size_t p = 0; p < fv.size(); ++p) {
      const Eigen::MatrixXd JtW = l.jacobians[p].transpose() * f->information();
      const int rp = c.of(fv[p]);
      b.segment(rp, JtW.rows()) += JtW * l.error;
      for (size_t q = 0; q < fv.size(); ++q)
        H.block(rp, c.of(fv[q]), JtW.rows(), l.jacobians[q].cols()) += JtW * l.jacobians[q];
    }
  }
  const int e = c.eliminated, k = c.total - e;
  MarginalInformation m;
  m.kept.assign(c.order.begin() + static_cast<long>(c.eliminated_variables), c.order.end());
  if (e == 0) {
    m.H = H, m.b = b;
    return m;
  }
  const Eigen::LDLT<Eigen::MatrixXd> Hee(symmetrized(H.topLeftCorner(e, e)));
  if (Hee.info() != Eigen::Success || !(Hee.vectorD().minCoeff() > 0))
    throw std::invalid_argument("marginalize: the eliminated variables are not determined by their factors");
  const Eigen::MatrixXd HeeInvHek = Hee.solve(H.topRightCorner(e, k));
  m.H = symmetrized(H.bottomRightCorner(k, k) - H.bottomLeftCorner(k, e) * HeeInvHek);
  m.b = b.tail(k) - HeeInvHek.transpose() * b.head(e);
  return m;
}

std::unique_ptr<LinearPriorFactor> marginalize(const std::vector<Variable>& vars,
                                               const std::vector<const Factor*>& factors,
                                               const std::vector<int>& eliminate) {
  MarginalInformation m = marginal_information(vars, factors, eliminate);
  if (m.kept.empty()) return nullptr;
  std::vector<Variable> x0;
  for (int v : m.kept) x0.push_back(vars[static_cast<size_t>(v)]);
  return LinearPriorFactor::from_hessian(std::move(m.kept), std::move(x0), m.H, m.b);
}

}  // namespace sextant::graph

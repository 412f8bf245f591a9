// LinearPriorFactor: its cost is the quadratic it was built from (e'e = r0'r0 + 2 b'd + d'H d), rank-deficient H
// keeps only the informative directions, its pose Jacobians match central differences; marginalize() of a linear
// problem leaves the kept variables' optimum that of the full problem.
#include "estimators/graph/linear_prior_factor.hpp"

#include "estimators/graph/numeric_jacobian.hpp"
#include "estimators/graph/optimizer.hpp"

#include <doctest/doctest.h>

#include <random>

using namespace sextant;
using namespace sextant::graph;
using sextant::test::jacobian_mismatch;

namespace {

Variable vec(int64_t id, const Eigen::Vector3d& x) {
  Variable v;
  v.id = id;
  v.kind = VariableKind::kVector3;
  v.point = x;
  return v;
}

Eigen::MatrixXd random_spd(std::mt19937& rng, int n) {
  std::normal_distribution<double> g;
  Eigen::MatrixXd A(n, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) A(r, c) = g(rng);
  return A * A.transpose() + Eigen::MatrixXd::Identity(n, n);
}

// e = x_j - x_i - z with information W: a linear factor between two vectors.
class Difference final : public Factor {
 public:
  Difference(int i, int j, Eigen::Vector3d z, Eigen::Matrix3d W) : Factor({i, j}, W), z_(std::move(z)) {}
  std::unique_ptr<Factor> clone() const override { return std::make_unique<Difference>(*this); }
  std::string type() const override { return "difference"; }
  void error(const std::vector<Variable>& v, Eigen::VectorXd& e) const override {
    e = v[static_cast<size_t>(variables()[1])].point - v[static_cast<size_t>(variables()[0])].point - z_;
  }
  void linearize(const std::vector<Variable>& v, Linearization& out) const override {
    error(v, out.error);
    out.jacobians[0] = -Eigen::Matrix3d::Identity();
    out.jacobians[1] = Eigen::Matrix3d::Identity();
  }

 private:
  Eigen::Vector3d z_;
};

}  // namespace

TEST_CASE("LinearPriorFactor: the cost of the quadratic it was built from, and only its informative directions") {
  std::mt19937 rng(2);
  const std::vector<Variable> x0 = {vec(0, {1, 2, 3}), vec(1, {-1, 0, 2})};
  const Eigen::MatrixXd H = random_spd(rng, 6);
  Eigen::VectorXd b(6);
  b << 0.3, -0.2, 0.5, 0.1, 0.0, -0.4;
  const auto f = LinearPriorFactor::from_hessian({0, 1}, x0, H, b);
  CHECK(f->residual_dim() == 6);
  Eigen::VectorXd e0(6);
  f->error(x0, e0);
  std::vector<Variable> x = x0;
  x[0].point += Eigen::Vector3d(0.1, -0.3, 0.2);
  x[1].point += Eigen::Vector3d(-0.2, 0.1, 0.4);
  Eigen::VectorXd d(6), e(6);
  d << x[0].point - x0[0].point, x[1].point - x0[1].point;
  f->error(x, e);
  CHECK(e.squaredNorm() == doctest::Approx(e0.squaredNorm() + 2 * b.dot(d) + d.dot(H * d)).epsilon(1e-12));
  CHECK(jacobian_mismatch(*f, x) < 1e-8);

  // A rank-3 H: three residuals, and no cost along its null space.
  Eigen::MatrixXd U = random_spd(rng, 6).leftCols(3);
  const Eigen::MatrixXd H3 = U * U.transpose();
  const auto g = LinearPriorFactor::from_hessian({0, 1}, x0, H3, H3 * Eigen::VectorXd::Ones(6));
  CHECK(g->residual_dim() == 3);
  Eigen::FullPivLU<Eigen::MatrixXd> lu(U.transpose());
  const Eigen::VectorXd null = lu.kernel().col(0);
  std::vector<Variable> along = x0;
  along[0].point += null.head<3>();
  along[1].point += null.tail<3>();
  Eigen::VectorXd ea(3), eb(3);
  g->error(x0, ea);
  g->error(along, eb);
  CHECK((ea - eb).norm() < 1e-9);
  CHECK_THROWS_AS(LinearPriorFactor::from_hessian({0, 1}, x0, -H, b), std::invalid_argument);
  CHECK_THROWS_AS(LinearPriorFactor::gaussian({0, 1}, x0, -H), std::invalid_argument);
}

TEST_CASE("LinearPriorFactor: on a pose, Jacobians through Jr^-1 against central differences") {
  Variable p;
  p.id = 0;
  p.kind = VariableKind::kPose3;
  p.pose3 = SE3::exp((Vector6d() << 1, 2, 3, 0.3, -0.2, 0.5).finished());
  std::mt19937 rng(4);
  const auto f = LinearPriorFactor::gaussian({0}, {p}, random_spd(rng, 6));
  std::vector<Variable> x = {p};
  Eigen::VectorXd e(6);
  f->error(x, e);
  CHECK(e.norm() < 1e-12);
  x[0].pose3 = x[0].pose3 * SE3::exp((Vector6d() << 0.4, -0.3, 0.2, 0.2, 0.3, -0.25).finished());
  CHECK(jacobian_mismatch(*f, x) < 1e-6);
}

TEST_CASE("marginalize: a linear chain's kept variables have the full problem's optimum") {
  std::mt19937 rng(9);
  std::normal_distribution<double> n;
  auto random3 = [&] { return Eigen::Vector3d(n(rng), n(rng), n(rng)); };
  // Chain 0 - 1 - 2 - 3 with a prior on 0 and a loop 0 - 3; eliminate 0 and 1.
  FactorGraph full;
  for (int k = 0; k < 4; ++k) full.add_variable(vec(k, random3()));
  std::vector<std::unique_ptr<Factor>> fs;
  fs.push_back(LinearPriorFactor::gaussian({0}, {vec(0, random3())}, random_spd(rng, 3)));
  for (int k = 0; k < 3; ++k) fs.push_back(std::make_unique<Difference>(k, k + 1, random3(), random_spd(rng, 3)));
  fs.push_back(std::make_unique<Difference>(0, 3, random3(), random_spd(rng, 3)));
  for (const auto& f : fs) full.add_factor(f->clone());
  OptimizerOptions o;
  REQUIRE(optimize(full, o).usable());

  // Marginalize 0 and 1 at the initial values (the problem is linear: the point does not matter), then solve the rest.
  FactorGraph initial;
  for (int k = 0; k < 4; ++k) initial.add_variable(vec(k, random3()));
  std::vector<const Factor*> touching = {fs[0].get(), fs[1].get(), fs[2].get(), fs[4].get()};
  const auto prior = marginalize(initial.variables(), touching, {0, 1});
  REQUIRE(prior);
  CHECK(prior->variables() == std::vector<int>{2, 3});  // kept in order of first appearance: 1-2's 2, then 0-3's 3
  FactorGraph reduced;
  reduced.add_variable(initial.variables()[2]);
  reduced.add_variable(initial.variables()[3]);
  reduced.add_factor(prior->rebind({0, 1}));
  reduced.add_factor(fs[3]->rebind({0, 1}));
  REQUIRE(optimize(reduced, o).usable());
  CHECK((reduced.variables()[0].point - full.variables()[2].point).norm() < 1e-9);
  CHECK((reduced.variables()[1].point - full.variables()[3].point).norm() < 1e-9);
  // Nothing determines an eliminated variable without factors.
  CHECK_THROWS_AS(marginalize(initial.variables(), {fs[3].get()}, {0}), std::invalid_argument);
}

TEST_CASE("optimize: a factor on six variables (the IMU factor's count) reaches the minimum of its quadratic") {
  // The normal equations once kept J'W of at most four variables per factor: six wrote past the end.
  std::mt19937 rng(6);
  FactorGraph g;
  std::vector<Variable> x0;
  for (int k = 0; k < 6; ++k) {
    g.add_variable(vec(k, Eigen::Vector3d::Zero()));
    x0.push_back(vec(k, Eigen::Vector3d(k, -k, 2.0 * k)));
  }
  g.add_factor(LinearPriorFactor::gaussian({0, 1, 2, 3, 4, 5}, x0, random_spd(rng, 18)));
  OptimizerOptions o;
  REQUIRE(optimize(g, o).usable());
  for (int k = 0; k < 6; ++k)
    CHECK((g.variables()[static_cast<size_t>(k)].point - x0[static_cast<size_t>(k)].point).norm() < 1e-9);
}

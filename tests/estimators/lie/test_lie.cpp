// One generic harness for every Lie group: each analytic Jacobian against central differences on the manifold,
// Exp/Log round trips near and far from the identity (rotations near pi included), and the adjoint identity.
#include "estimators/lie/se2.hpp"
#include "estimators/lie/se3.hpp"

#include <doctest/doctest.h>

#include <random>

using namespace sextant;

namespace {

template <class G>
struct Traits;

template <>
struct Traits<SE3> {
  static constexpr int kDof = 6;
  using Tangent = Eigen::Matrix<double, 6, 1>;
  using Jac = Eigen::Matrix<double, 6, 6>;
  static SE3 exp(const Tangent& t, Jac* J = nullptr) { return SE3::exp(t, J); }
  static Tangent log(const SE3& x, Jac* J = nullptr) { return x.log(J); }
  static Jac adjoint(const SE3& x) { return x.adjoint(); }
  static constexpr double kMaxAngle = M_PI;
  static Tangent with_angle(Tangent t, double angle) {
    t.tail<3>() = t.tail<3>().normalized() * angle;
    return t;
  }
  static double angle(const Tangent& t) { return t.tail<3>().norm(); }
};

template <>
struct Traits<SE2> {
  static constexpr int kDof = 3;
  using Tangent = Eigen::Vector3d;
  using Jac = Eigen::Matrix3d;
  static SE2 exp(const Tangent& t, Jac* J = nullptr) { return SE2::exp(t, J); }
  static Tangent log(const SE2& x, Jac* J = nullptr) { return x.log(J); }
  static Jac adjoint(const SE2& x) { return x.adjoint(); }
  static Tangent with_angle(Tangent t, double angle) {
    t.z() = angle;
    return t;
  }
  static double angle(const Tangent& t) { return std::abs(t.z()); }
};

template <>
struct Traits<SO3> {
  static constexpr int kDof = 3;
  using Tangent = Eigen::Vector3d;
  using Jac = Eigen::Matrix3d;
  static SO3 exp(const Tangent& t, Jac* J = nullptr) { return SO3::exp(t, J); }
  static Tangent log(const SO3& x, Jac* J = nullptr) { return x.log(J); }
  static Jac adjoint(const SO3& x) { return x.adjoint(); }
  static Tangent with_angle(Tangent t, double angle) { return t.normalized() * angle; }
  static double angle(const Tangent& t) { return t.norm(); }
};

template <class G>
using T = Traits<G>;

template <class G>
typename T<G>::Tangent random_tangent(std::mt19937& rng, double scale) {
  std::normal_distribution<double> n(0, scale);
  typename T<G>::Tangent t;
  for (int i = 0; i < T<G>::kDof; ++i) t[i] = n(rng);
  return t;
}

// d f(X (+) d) / d d at d = 0, for f: G -> H, by central differences of the right-perturbed output.
template <class G, class H, class F>
Eigen::MatrixXd numerical_jacobian(const G& x, F f) {
  const double h = 1e-6;
  const H y = f(x);
  Eigen::MatrixXd J(T<H>::kDof, T<G>::kDof);
  for (int i = 0; i < T<G>::kDof; ++i) {
    typename T<G>::Tangent e = T<G>::Tangent::Zero();
    e[i] = h;
    const auto plus = T<H>::log(y.inverse() * f(x * T<G>::exp(e)));
    const auto minus = T<H>::log(y.inverse() * f(x * T<G>::exp(-e)));
    J.col(i) = (plus - minus) / (2 * h);
  }
  return J;
}

template <class G>
double distance(const G& a, const G& b) {
  return T<G>::log(a.inverse() * b).norm();
}

template <class G>
void check_group(uint32_t seed) {
  std::mt19937 rng(seed);
  // Scales: near the identity, moderate, large; plus angles placed near pi and near zero.
  for (double scale : {1e-9, 1e-4, 0.3, 1.5}) {
    for (int trial = 0; trial < 20; ++trial) {
      auto tau = random_tangent<G>(rng, scale);
      if (trial == 0) tau = T<G>::with_angle(tau, M_PI - 1e-7);
      if (trial == 1) tau = T<G>::with_angle(tau, M_PI - 1e-3);
      if (trial == 2) tau = T<G>::with_angle(tau, 1e-10);
      if (T<G>::angle(tau) >= M_PI) tau = T<G>::with_angle(tau, std::fmod(T<G>::angle(tau), M_PI));
      CAPTURE(scale);
      CAPTURE(trial);
      const G x = T<G>::exp(tau);

      // Log(Exp(tau)) = tau for angles below pi.
      CHECK((T<G>::log(x) - tau).norm() <= 1e-9 * std::max(1.0, tau.norm()));

      // Exp's right Jacobian: Exp(tau + d) ~ Exp(tau) Exp(Jr d).
      typename T<G>::Jac Jr;
      T<G>::exp(tau, &Jr);
      const double h = 1e-6;
      typename T<G>::Jac Jnum;
      for (int i = 0; i < T<G>::kDof; ++i) {
        typename T<G>::Tangent e = T<G>::Tangent::Zero();
        e[i] = h;
        Jnum.col(i) =
            (T<G>::log(x.inverse() * T<G>::exp(tau + e)) - T<G>::log(x.inverse() * T<G>::exp(tau - e))) / (2 * h);
      }
      if (T<G>::angle(tau) < M_PI - 1e-4) CHECK((Jr - Jnum).norm() < 1e-6 * std::max(1.0, Jr.norm()));

      // Log's Jacobian is Jr^-1.
      typename T<G>::Jac Jri;
      T<G>::log(x, &Jri);
      if (T<G>::angle(tau) < M_PI - 1e-4) CHECK((Jri * Jr - T<G>::Jac::Identity()).norm() < 1e-6);

      // Adjoint: X Exp(v) = Exp(Ad_X v) X.
      const auto v = random_tangent<G>(rng, 0.2);
      CHECK(distance<G>(x * T<G>::exp(v), T<G>::exp(T<G>::adjoint(x) * v) * x) < 1e-9);
    }
  }
}

template <class G>
void check_operation_jacobians(uint32_t seed) {
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 30; ++trial) {
    const double scale = trial < 10 ? 0.1 : trial < 20 ? 1.0 : 2.5;
    G a = T<G>::exp(random_tangent<G>(rng, scale));
    G b = T<G>::exp(random_tangent<G>(rng, scale));
    typename T<G>::Jac Ja, Jb, Ji;
    a.compose(b, &Ja, &Jb);
    CHECK((Ja - numerical_jacobian<G, G>(a, [&](const G& x) { return x * b; })).norm() <
          1e-6 * std::max(1.0, Ja.norm()));
    CHECK((Jb - numerical_jacobian<G, G>(b, [&](const G& x) { return a * x; })).norm() < 1e-6);
    a.between(b, &Ja, &Jb);
    CHECK((Ja - numerical_jacobian<G, G>(a, [&](const G& x) { return x.inverse() * b; })).norm() <
          1e-6 * std::max(1.0, Ja.norm()));
    CHECK((Jb - numerical_jacobian<G, G>(b, [&](const G& x) { return a.inverse() * x; })).norm() < 1e-6);
    a.inverse(&Ji);
    CHECK((Ji - numerical_jacobian<G, G>(a, [](const G& x) { return x.inverse(); })).norm() <
          1e-6 * std::max(1.0, Ji.norm()));
  }
}

}  // namespace

TEST_CASE("SO3: Exp/Log round trips, Exp and Log Jacobians, adjoint") { check_group<SO3>(1); }
TEST_CASE("SE3: Exp/Log round trips, Exp and Log Jacobians, adjoint") { check_group<SE3>(2); }
TEST_CASE("SE2: Exp/Log round trips, Exp and Log Jacobians, adjoint") { check_group<SE2>(3); }
TEST_CASE("SE3: compose, between and inverse Jacobians") { check_operation_jacobians<SE3>(4); }
TEST_CASE("SE2: compose, between and inverse Jacobians") { check_operation_jacobians<SE2>(5); }

TEST_CASE("SE3 and SE2 act on points, with Jacobians") {
  std::mt19937 rng(6);
  for (int trial = 0; trial < 20; ++trial) {
    const SE3 x = SE3::exp(random_tangent<SE3>(rng, 1.0));
    const Eigen::Vector3d p(1.5, -0.3, 2.0);
    Eigen::Matrix<double, 3, 6> Jx;
    Eigen::Matrix3d Jp;
    const Eigen::Vector3d y = x.act(p, &Jx, &Jp);
    CHECK((y - x.isometry() * p).norm() < 1e-12);
    const double h = 1e-6;
    for (int i = 0; i < 6; ++i) {
      Vector6d e = Vector6d::Zero();
      e[i] = h;
      const Eigen::Vector3d d = ((x * SE3::exp(e)).act(p) - (x * SE3::exp(-e)).act(p)) / (2 * h);
      CHECK((d - Jx.col(i)).norm() < 1e-6);
    }
    CHECK((Jp - x.rotation().matrix()).norm() < 1e-12);

    const SE2 x2 = SE2::exp(random_tangent<SE2>(rng, 1.0));
    const Eigen::Vector2d q(0.7, -1.1);
    Eigen::Matrix<double, 2, 3> J2;
    x2.act(q, &J2);
    for (int i = 0; i < 3; ++i) {
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[i] = h;
      const Eigen::Vector2d d = ((x2 * SE2::exp(e)).act(q) - (x2 * SE2::exp(-e)).act(q)) / (2 * h);
      CHECK((d - J2.col(i)).norm() < 1e-6);
    }
  }
}

TEST_CASE("rotations near pi: Log picks the angle in [0, pi] and the two quaternion signs agree") {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
  const SO3 r = SO3::exp(axis * (M_PI - 1e-9));
  CHECK(r.log().norm() == doctest::Approx(M_PI - 1e-9).epsilon(1e-12));
  const SO3 flipped(Eigen::Quaterniond(-r.quaternion().coeffs()));
  CHECK((flipped.log() - r.log()).norm() < 1e-9);
  const SO3 exactly_pi(Eigen::Quaterniond(0, axis.x(), axis.y(), axis.z()));
  CHECK(exactly_pi.log().norm() == doctest::Approx(M_PI));
  CHECK(SE2(0, 0, M_PI).angle() == doctest::Approx(M_PI));
  CHECK(SE2(0, 0, -M_PI).angle() == doctest::Approx(M_PI));  // (-pi, pi]
  CHECK(wrap_angle(3 * M_PI / 2) == doctest::Approx(-M_PI / 2));
}

TEST_CASE("SE2 embeds in SE3 and back") {
  const SE2 a(1.0, -2.0, 0.7);
  const SE3 b = a.to_se3();
  CHECK(b.translation().z() == 0);
  const SE2 c = SE2::from_se3(b);
  CHECK(c.angle() == doctest::Approx(0.7));
  CHECK((c.translation() - a.translation()).norm() < 1e-15);
  // Composition commutes with the embedding.
  const SE2 d(0.3, 0.4, -1.2);
  CHECK((SE2::from_se3(a.to_se3() * d.to_se3()).log() - (a * d).log()).norm() < 1e-12);
}

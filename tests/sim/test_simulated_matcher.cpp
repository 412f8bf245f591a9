// The simulated front end (sextant matcher): interpolated truth, the noise of correct answers (mean and covariance
// over many draws), failure and wrong-match fractions within binomial bounds, wrong answers really wrong, the
// planar convention, unanswerable requests counted, determinism, and reading the truth from logs.
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "sim/simulated_matcher.hpp"
#include "sim/simulator.hpp"

#include <doctest/doctest.h>

#include <sextant/truth_t.hpp>

#include <cmath>
#include <filesystem>
#include <limits>
#include <unistd.h>

using namespace sextant;
using tools::InterpolatedTrajectory;
using tools::MatcherTruth;
using tools::SimulatedMatcher;
using tools::SimulatedMatcherOptions;

namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;

std::string temp(const std::string& n) {
  return (std::filesystem::temp_directory_path() / ("sextant_matcher_" + std::to_string(::getpid()) + "_" + n))
      .string();
}

// A climbing helix with a pitch oscillation: the pose at t seconds after kT0.
SE3 helix(double t) {
  const double yaw = 0.2 * t + M_PI / 2, pitch = 0.1 * std::sin(0.5 * t);
  const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()));
  return SE3(q, Eigen::Vector3d(5 * std::cos(0.2 * t), 5 * std::sin(0.2 * t), 0.1 * t));
}

int64_t at_s(double t) { return kT0 + static_cast<int64_t>(std::llround(t * 1e6)); }

// 10 Hz samples over [0, 60] s.
MatcherTruth helix_truth(bool planar = false) {
  std::vector<std::pair<int64_t, SE3>> s;
  for (int i = 0; i <= 600; ++i) s.push_back({at_s(i * 0.1), helix(i * 0.1)});
  return {InterpolatedTrajectory(std::move(s)), planar};
}

engine::MatchRequest request(double tb, double ta, int64_t id = 7, const std::string& source = "robot1") {
  engine::MatchRequest r;
  r.utime = at_s(ta);
  r.source = source;
  r.request_id = id;
  r.kind = "local";
  r.a = {12, at_s(ta), {}};
  r.b = {3, at_s(tb), {}};
  return r;
}

SimulatedMatcher matcher_for(MatcherTruth truth, const SimulatedMatcherOptions& o) {
  std::map<std::string, MatcherTruth> m;
  m["robot1"] = std::move(truth);
  return SimulatedMatcher(std::move(m), o);
}

SE3 to_se3(const engine::Pose& p) { return SE3(p.orientation, p.position); }

// Rotation angle between two rotations.
double angle_between(const SO3& a, const SO3& b) { return (a.inverse() * b).log().norm(); }

}  // namespace

TEST_CASE("interpolated trajectory: exact at the stamps, linear + slerp between, nothing outside the span") {
  const SE3 p0(SO3::exp(Eigen::Vector3d(0.1, -0.2, 0.3)), Eigen::Vector3d(1, 2, 3));
  const SE3 p1(SO3::exp(Eigen::Vector3d(0.5, 0.4, -1.2)), Eigen::Vector3d(2, 0, 7));
  const SE3 p2(SO3::exp(Eigen::Vector3d(-2.0, 0.4, 1.0)), Eigen::Vector3d(-3, 1, 0));
  // Out of order and with a duplicate stamp (the first of the two is kept) and a non-finite sample.
  const SE3 bad(SO3(), Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0));
  const InterpolatedTrajectory tr({{300, p2}, {100, p0}, {200, p1}, {200, p2}, {250, bad}});
  CHECK(tr.size() == 3);
  CHECK(tr.dropped() == 1);
  CHECK(tr.first_utime() == 100);
  CHECK(tr.last_utime() == 300);
  for (const auto& [t, p] : {std::pair{int64_t{100}, p0}, std::pair{int64_t{200}, p1}, std::pair{int64_t{300}, p2}}) {
    const auto x = tr.at(t);
    REQUIRE(x);
    CHECK(x->translation() == p.translation());
    CHECK(x->rotation().quaternion().coeffs() == p.rotation().quaternion().coeffs());
  }
  CHECK(!tr.at(99));
  CHECK(!tr.at(301));
  CHECK(!InterpolatedTrajectory().at(0));
  // Between: the position on the segment, the rotation R0 Exp(s Log(R0^-1 R1)) (the geodesic).
  for (const double s : {0.25, 0.5, 0.9}) {
    const auto x = tr.at(200 + static_cast<int64_t>(s * 100));
    REQUIRE(x);
    CHECK((x->translation() - ((1 - s) * p1.translation() + s * p2.translation())).norm() < 1e-12);
    const SO3 expected = p1.rotation() * SO3::exp(s * (p1.rotation().inverse() * p2.rotation()).log());
    CHECK(angle_between(x->rotation(), expected) < 1e-9);
  }
}

TEST_CASE("simulated matcher: correct answers are the true relative pose with noise of the stated covariance") {
  SimulatedMatcherOptions o;
  o.sigma_t = 0.1;
  o.sigma_r = 0.03;
  o.seed = 3;
  auto m = matcher_for(helix_truth(), o);
  const SE3 truth = helix(10).between(helix(40));  // both at truth stamps: no interpolation involved
  const int n = 4000;
  std::vector<Vector6d> etas;
  for (int i = 0; i < n; ++i) {
    const auto lc = m.answer(request(10, 40, i));
    REQUIRE(lc);
    if (i == 0) {
      CHECK(lc->utime_from == at_s(10));
      CHECK(lc->utime_to == at_s(40));
      CHECK(lc->keyframe_from == 3);
      CHECK(lc->keyframe_to == 12);
      CHECK(lc->request_id == 0);
      CHECK(lc->source == "robot1");
      CHECK(!lc->planar);
      CHECK(lc->utime == at_s(40));
      CHECK(lc->matcher == "sextant-matcher");
      Matrix6d info = Matrix6d::Zero();
      info.diagonal() << 100, 100, 100, 1 / 9e-4, 1 / 9e-4, 1 / 9e-4;
      CHECK((lc->information - info).norm() < 1e-6);
      // What the daemon receives: the codec accepts it.
      CHECK(std::holds_alternative<engine::Event>(runtime::to_event(runtime::to_message(*lc, "test", 0))));
    }
    etas.push_back(truth.between(to_se3(lc->relative)).log());
  }
  Vector6d mean = Vector6d::Zero();
  for (const auto& e : etas) mean += e / n;
  Matrix6d cov = Matrix6d::Zero();
  for (const auto& e : etas) cov += (e - mean) * (e - mean).transpose() / (n - 1);
  for (int i = 0; i < 6; ++i) {
    const double s = i < 3 ? o.sigma_t : o.sigma_r;
    CAPTURE(i);
    CHECK(std::abs(mean[i]) < 4.5 * s / std::sqrt(n));
    CHECK(std::abs(cov(i, i) / (s * s) - 1) < 4.5 * std::sqrt(2.0 / n));  // sample variance: sd sqrt(2/n)
    for (int j = 0; j < i; ++j) {
      const double sj = j < 3 ? o.sigma_t : o.sigma_r;
      CHECK(std::abs(cov(i, j) / (s * sj)) < 4.5 / std::sqrt(n));  // sample correlation: sd 1/sqrt(n)
    }
  }
}

TEST_CASE("simulated matcher: an answer between truth stamps uses the interpolated truth") {
  SimulatedMatcherOptions o;
  o.sigma_t = 1e-6;
  o.sigma_r = 1e-7;
  auto m = matcher_for(helix_truth(), o);
  auto r = request(10.03, 40.07);
  r.utime = 0;  // a request without its own time: the answer takes utime_a
  const auto lc = m.answer(r);
  REQUIRE(lc);
  CHECK(lc->utime == at_s(40.07));
  // Independent: interpolate by hand between the 10 Hz samples.
  const auto interp = [](double t) {
    const double t0 = std::floor(t * 10 + 1e-9) / 10, s = (t - t0) / 0.1;
    const SE3 a = helix(t0), b = helix(t0 + 0.1);
    return SE3(a.rotation().quaternion().slerp(s, b.rotation().quaternion()),
               (1 - s) * a.translation() + s * b.translation());
  };
  const SE3 expected = interp(10.03).between(interp(40.07));
  CHECK((to_se3(lc->relative).translation() - expected.translation()).norm() < 1e-5);
  CHECK(angle_between(to_se3(lc->relative).rotation(), expected.rotation()) < 1e-6);
  // And it is not the nearest sample's pose.
  CHECK((helix(10).between(helix(40.1)).translation() - expected.translation()).norm() > 1e-2);
}

TEST_CASE("simulated matcher: failure and wrong-match fractions within binomial bounds, wrong answers are wrong") {
  const SimulatedMatcherOptions o{
      .sigma_t = 0.01, .sigma_r = 0.001, .failure_rate = 0.2, .wrong_rate = 0.1, .seed = 99};
  auto m = matcher_for(helix_truth(), o);
  const int n = 6000;
  int none = 0, far = 0, near = 0;
  for (int i = 0; i < n; ++i) {
    const double tb = 1 + (i % 45), ta = tb + 5 + (i % 7);  // ta <= 57 s: inside the truth
    const auto lc = m.answer(request(tb, ta, i));
    if (!lc) {
      ++none;
      continue;
    }
    const SE3 d = helix(tb).between(helix(ta)).between(to_se3(lc->relative));
    const double et = d.translation().norm(), er = d.rotation().log().norm();
    if (et > 0.9 || er > 0.45)
      ++far;  // wrong: at least 1 m or 0.5 rad off (noise is ~0.02 m, 0.002 rad)
    else if (et < 0.1 && er < 0.01)
      ++near;
    CHECK((lc->information.diagonal()[0] == doctest::Approx(1e4)));  // wrong ones look the same on the wire
  }
  const auto& c = m.counts();
  CHECK(c.requests == n);
  CHECK(c.failed == none);
  CHECK(c.wrong == far);
  CHECK(c.answered == near);
  CHECK(c.answered + c.wrong + c.failed == n);
  const auto within = [n](int64_t count, double p) {
    return std::abs(count - n * p) < 4.5 * std::sqrt(n * p * (1 - p));
  };
  CHECK(within(c.failed, 0.2));
  CHECK(within(c.wrong, 0.1));
}

TEST_CASE("simulated matcher: a body that never moves still gets wrong answers, displaced by the fallback") {
  std::vector<std::pair<int64_t, SE3>> still;
  for (int i = 0; i <= 100; ++i) still.push_back({at_s(i * 0.1), SE3(SO3(), Eigen::Vector3d(1, 1, 0))});
  SimulatedMatcherOptions o;
  o.sigma_t = 1e-6;
  o.sigma_r = 1e-7;
  o.wrong_rate = 1.0;
  auto m = matcher_for({InterpolatedTrajectory(still), false}, o);
  for (int i = 0; i < 20; ++i) {
    const auto lc = m.answer(request(1, 5, i));
    REQUIRE(lc);
    const SE3 x = to_se3(lc->relative);
    CHECK(x.translation().norm() == doctest::Approx(2 * o.wrong_min_translation).epsilon(1e-5));
    CHECK(x.rotation().log().norm() == doctest::Approx(2 * o.wrong_min_rotation).epsilon(1e-5));
  }
  CHECK(m.counts().wrong == 20);
}

TEST_CASE("simulated matcher: planar bodies get planar answers (x, y, yaw, information at 0, 1, 5)") {
  SimulatedMatcherOptions o;
  o.sigma_t = 0.05;
  o.sigma_r = 0.02;
  auto m = matcher_for(helix_truth(/*planar=*/true), o);
  const SE2 truth = SE2::from_se3(helix(10)).between(SE2::from_se3(helix(40)));
  const int n = 3000;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), var = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const auto lc = m.answer(request(10, 40, i));
    REQUIRE(lc);
    CHECK(lc->planar);
    CHECK(lc->relative.position.z() == 0);
    CHECK(std::abs(lc->relative.orientation.x()) + std::abs(lc->relative.orientation.y()) < 1e-12);
    if (i == 0) {
      Matrix6d info = Matrix6d::Zero();
      info(0, 0) = info(1, 1) = 1 / 0.0025;
      info(5, 5) = 1 / 0.0004;
      CHECK((lc->information - info).norm() < 1e-6);
      CHECK(std::holds_alternative<engine::Event>(runtime::to_event(runtime::to_message(*lc, "test", 0))));
    }
    const Eigen::Vector3d eta = truth.between(SE2::from_se3(to_se3(lc->relative))).log();
    mean += eta / n;
    var += eta.cwiseProduct(eta) / n;
  }
  const Eigen::Vector3d sd(o.sigma_t, o.sigma_t, o.sigma_r);
  for (int i = 0; i < 3; ++i) {
    CHECK(std::abs(mean[i]) < 4.5 * sd[i] / std::sqrt(n));
    CHECK(std::abs(var[i] / (sd[i] * sd[i]) - 1) < 4.5 * std::sqrt(2.0 / n));
  }
}

TEST_CASE("simulated matcher: unanswerable requests are counted and use no random draw") {
  SimulatedMatcherOptions o;
  o.failure_rate = 0.3;
  o.wrong_rate = 0.2;
  auto plain = matcher_for(helix_truth(), o);
  auto interrupted = matcher_for(helix_truth(), o);
  for (int i = 0; i < 50; ++i) {
    const auto r = request(5 + i * 0.5, 40, i);
    // Outside the span (before the first or after the last stamp), unknown body, equal times, a non-positive time.
    CHECK(!interrupted.answer(request(-1, 40)));
    CHECK(!interrupted.answer(request(10, 60.1)));
    CHECK(!interrupted.answer(request(10, 40, 1, "robot2")));
    CHECK(!interrupted.answer(request(20, 20)));
    auto zero = r;
    zero.b.utime = 0;
    CHECK(!interrupted.answer(zero));
    const auto x = plain.answer(r), y = interrupted.answer(r);
    REQUIRE(x.has_value() == y.has_value());
    if (x) CHECK(x->relative.position == y->relative.position);
  }
  CHECK(interrupted.counts().out_of_span == 100);
  CHECK(interrupted.counts().invalid == 150);
  CHECK(interrupted.counts().requests == 300);
  CHECK(plain.counts().out_of_span + plain.counts().invalid == 0);
}

TEST_CASE("simulated matcher: deterministic for a seed, different for another") {
  SimulatedMatcherOptions o;
  o.failure_rate = 0.1;
  o.wrong_rate = 0.1;
  o.seed = 5;
  auto a = matcher_for(helix_truth(), o), b = matcher_for(helix_truth(), o);
  o.seed = 6;
  auto c = matcher_for(helix_truth(), o);
  int differ = 0;
  for (int i = 0; i < 200; ++i) {
    const auto r = request(1 + i * 0.2, 50, i);
    const auto x = a.answer(r), y = b.answer(r), z = c.answer(r);
    REQUIRE(x.has_value() == y.has_value());
    if (x) {
      CHECK(x->relative.position == y->relative.position);
      CHECK(x->relative.orientation.coeffs() == y->relative.orientation.coeffs());
    }
    differ += x.has_value() != z.has_value() || (x && x->relative.position != z->relative.position);
  }
  CHECK(differ > 150);
}

TEST_CASE("simulated matcher: options are validated") {
  const auto bad = [](SimulatedMatcherOptions o) { CHECK_THROWS_AS(SimulatedMatcher({}, o), std::invalid_argument); };
  SimulatedMatcherOptions o;
  o.sigma_t = 0;
  bad(o);
  o = {};
  o.sigma_r = std::numeric_limits<double>::quiet_NaN();
  bad(o);
  o = {};
  o.failure_rate = 0.7, o.wrong_rate = 0.4;
  bad(o);
  o = {};
  o.wrong_rate = -0.1;
  bad(o);
  o = {};
  o.wrong_min_translation = -1;
  bad(o);
}

TEST_CASE("matcher truth from logs: simulate's planar and spatial runs, a truth-only log, and a log without truth") {
  for (const std::string scenario : {"planar", "spatial"}) {
    CAPTURE(scenario);
    const std::string path = temp(scenario + ".lcm");
    tools::SimulationOptions so;
    so.scenario = tools::scenario_from_name(scenario);
    so.duration_s = 5;
    so.landmarks = 0, so.sensors = 2, so.targets = 0;
    tools::SimulationSummary summary;
    {
      runtime::LogWriter w(path);
      summary = tools::simulate(so, w);
    }
    const auto truth = tools::read_matcher_truth(path);
    REQUIRE(truth.size() == 1);
    const MatcherTruth& t = truth.at("robot1");
    CHECK(t.planar == (scenario == "planar"));
    REQUIRE(t.trajectory.size() == summary.robot_truth.size());
    for (size_t i = 0; i < summary.robot_truth.size(); i += 37) {
      const auto& [utime, pose] = summary.robot_truth[i];
      const auto x = t.trajectory.at(utime);
      REQUIRE(x);
      CHECK((x->translation() - pose.position).norm() < 1e-12);
      CHECK(x->rotation().quaternion().angularDistance(pose.orientation) < 1e-9);
    }
    std::filesystem::remove(path);
  }
  // Truth only: planar from the geometry.
  for (const double z : {0.0, 0.5}) {
    const std::string path = temp("truth_only.lcm");
    {
      runtime::LogWriter w(path);
      for (int i = 0; i < 10; ++i) {
        sextant::truth_t m{};
        m.utime = at_s(i);
        m.kind = "robot";
        m.source = "bot";
        m.position[0] = i, m.position[2] = z;
        m.orientation[0] = std::cos(0.05 * i), m.orientation[3] = std::sin(0.05 * i);
        w.write(m.utime, "GROUND_TRUTH", m);
        m.kind = "landmark";  // ignored
        w.write(m.utime, "GROUND_TRUTH", m);
      }
    }
    const auto truth = tools::read_matcher_truth(path);
    REQUIRE(truth.count("bot") == 1);
    CHECK(truth.at("bot").planar == (z == 0.0));
    CHECK(truth.at("bot").trajectory.size() == 10);
    std::filesystem::remove(path);
  }
  const std::string empty = temp("empty.lcm");
  { runtime::LogWriter w(empty); }
  CHECK_THROWS_AS(tools::read_matcher_truth(empty), std::runtime_error);
  std::filesystem::remove(empty);
  CHECK_THROWS(tools::read_matcher_truth(temp("does_not_exist.lcm")));
}

TEST_CASE("simulated matcher: an inter-robot request is answered as a loop from b's body to a's, from both truths") {
  SimulatedMatcherOptions o;
  o.sigma_t = 1e-6;
  o.sigma_r = 1e-7;
  std::map<std::string, MatcherTruth> truths;
  truths["robot1"] = helix_truth();
  std::vector<std::pair<int64_t, SE3>> other;  // robot2: the helix shifted by 3 m in y and turned by 1 rad
  const SE3 shift(SO3::exp(Eigen::Vector3d(0, 0, 1)), Eigen::Vector3d(0, 3, 0));
  for (int i = 0; i <= 600; ++i) other.push_back({at_s(i * 0.1), shift * helix(i * 0.1)});
  truths["robot2"] = {InterpolatedTrajectory(std::move(other)), false};
  SimulatedMatcher m(std::move(truths), o);
  auto r = request(20, 20);  // the same time for two bodies is a valid inter-robot request
  r.source_b = "robot2";
  const auto lc = m.answer(r);
  REQUIRE(lc);
  CHECK(lc->source == "robot2");
  CHECK(lc->source_to == "robot1");
  const SE3 expected = (shift * helix(20)).between(helix(20));
  CHECK((to_se3(lc->relative).translation() - expected.translation()).norm() < 1e-5);
  r.source_b = "robot9";  // no truth of b's body
  CHECK_FALSE(m.answer(r));
  CHECK(m.counts().invalid == 1);
}

// Late measurements: inputs arriving out of order inside the window give exactly the state in-order processing
// gives; inputs older than the window are refused; the history stays bounded.
#include "estimators/filter/measurement_history.hpp"
#include "estimators/filter/planar_ekf.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <variant>

using namespace sextant;
using namespace sextant::filter;

namespace {

struct Increment {
  SE2 delta;
  Eigen::Matrix3d Q;
};
struct Sight {
  int64_t id;
  double range, bearing;
};
using Input = std::variant<Increment, Sight>;
struct Stamped {
  int64_t utime;
  int rank;
  Input input;
};

struct State {
  PlanarEkf ekf;
  int64_t applied = 0;
};

State initial_state() {
  State s;
  s.ekf.set_known_landmark(0, {5, 0});
  s.ekf.initialize(SE2(0, 0, 0), Eigen::Matrix3d::Identity() * 1e-4);
  return s;
}

void apply(State& s, const Input& in) {
  ++s.applied;
  if (const auto* i = std::get_if<Increment>(&in))
    s.ekf.predict(i->delta, i->Q);
  else {
    const auto& z = std::get<Sight>(in);
    s.ekf.observe(z.id, z.range, z.bearing, Eigen::Vector2d(0.01, 0.0004).asDiagonal());
  }
}

// A robot driving a circle at 50 Hz odometry among 4 landmarks (one known), sightings at 10 Hz.
std::vector<Stamped> make_run(int seconds, uint64_t seed) {
  std::mt19937 rng(static_cast<unsigned>(seed));
  std::normal_distribution<double> n(0, 1);
  const std::vector<Eigen::Vector2d> lm = {{5, 0}, {0, 5}, {-5, 0}, {2, -4}};
  std::vector<Stamped> out;
  SE2 truth(0, 0, 0);
  const SE2 step(0.04, 0, 0.01);
  for (int k = 1; k <= 50 * seconds; ++k) {
    const int64_t t = int64_t{20'000} * k;
    truth = truth * step;
    out.push_back({t, 0,
                   Increment{step * SE2::exp(Eigen::Vector3d(0.002 * n(rng), 0.002 * n(rng), 0.001 * n(rng))),
                             Eigen::Vector3d(4e-6, 4e-6, 1e-6).asDiagonal()}});
    if (k % 5 == 0) {
      const Eigen::Vector3d xt(truth.translation().x(), truth.translation().y(), truth.angle());
      for (size_t i = 0; i < lm.size(); ++i) {
        const Eigen::Vector2d z = PlanarEkf::observation(xt, lm[i], nullptr, nullptr);
        out.push_back({t, 1 + static_cast<int>(i),
                       Sight{static_cast<int64_t>(i), z[0] + 0.1 * n(rng),
                             z[1] + 0.02 * n(rng)}});  // distinct ranks: a fixed order at equal stamps
      }
    }
  }
  return out;
}

}  // namespace

TEST_CASE("late measurements inside the window give exactly the in-order state") {
  const auto run = make_run(10, 3);
  MeasurementHistory<State, Input> in_order(500'000, initial_state());
  for (const auto& s : run)
    CHECK(in_order.add(s.utime, s.rank, s.input, apply) == decltype(in_order)::Outcome::applied);

  // Arrival order: every input delayed by a random lag of up to 0.4 s (window 0.5 s), sightings more than odometry.
  std::mt19937 rng(11);
  std::vector<std::pair<int64_t, size_t>> arrival;
  for (size_t i = 0; i < run.size(); ++i) {
    const int64_t lag =
        static_cast<int64_t>(std::uniform_real_distribution<double>(0, run[i].rank >= 1 ? 400'000 : 100'000)(rng));
    arrival.push_back({run[i].utime + lag, i});
  }
  std::sort(arrival.begin(), arrival.end());
  MeasurementHistory<State, Input> late(500'000, initial_state());
  int reapplied = 0;
  for (const auto& [t, i] : arrival) {
    const auto o = late.add(run[i].utime, run[i].rank, run[i].input, apply);
    REQUIRE(o != decltype(late)::Outcome::too_late);
    reapplied += o == decltype(late)::Outcome::reapplied;
  }
  CHECK(reapplied > 100);
  const auto& a = in_order.state().ekf;
  const auto& b = late.state().ekf;
  REQUIRE(a.state().size() == b.state().size());
  CHECK((a.state() - b.state()).cwiseAbs().maxCoeff() <= 1e-12);
  CHECK((a.covariance() - b.covariance()).cwiseAbs().maxCoeff() <= 1e-12);
  CHECK(a.landmark_count() == 3);
  // Re-application ran many more steps, but the state itself counts each input once.
  CHECK(late.state().applied == in_order.state().applied);
  // Bounded: about the window's worth of inputs (0.5 s + one checkpoint interval: at most 0.5625 s of 90 per s).
  CHECK(late.inputs() <= 52u);
  CHECK(late.checkpoints() <= 11u);
}

TEST_CASE("an input older than the window is refused and leaves the state untouched") {
  const auto run = make_run(2, 5);
  MeasurementHistory<State, Input> h(200'000, initial_state());
  const Stamped* held = nullptr;
  std::vector<Stamped> kept;
  for (const auto& s : run) {
    if (held == nullptr && s.rank >= 1 && s.utime >= 500'000) {
      held = &s;  // arrives at the end, 1.5 s late
      continue;
    }
    kept.push_back(s);
    h.add(s.utime, s.rank, s.input, apply);
  }
  REQUIRE(held != nullptr);
  const Eigen::VectorXd before = h.state().ekf.state();
  CHECK(h.add(held->utime, held->rank, held->input, apply) == decltype(h)::Outcome::too_late);
  CHECK(h.state().ekf.state() == before);
  // The same as never having seen it.
  MeasurementHistory<State, Input> ref(200'000, initial_state());
  for (const auto& s : kept) ref.add(s.utime, s.rank, s.input, apply);
  CHECK((ref.state().ekf.state() - h.state().ekf.state()).cwiseAbs().maxCoeff() <= 1e-12);
  // Exactly at the window edge it is still accepted.
  const int64_t edge = h.newest() - 200'000;
  CHECK(h.add(edge, 1, Sight{0, 5.0, 0.0}, apply) == decltype(h)::Outcome::reapplied);
  CHECK(h.add(edge - 1, 1, Sight{0, 5.0, 0.0}, apply) == decltype(h)::Outcome::too_late);
}

TEST_CASE("a late input before the first one and a zero window") {
  MeasurementHistory<State, Input> h(0, initial_state());
  CHECK(h.add(1000, 0, Increment{SE2(0.1, 0, 0), Eigen::Matrix3d::Identity() * 1e-6}, apply) ==
        decltype(h)::Outcome::applied);
  CHECK(h.add(900, 0, Increment{SE2(0.1, 0, 0), Eigen::Matrix3d::Identity() * 1e-6}, apply) ==
        decltype(h)::Outcome::too_late);
  // Same stamp as the newest, higher rank: in order.  In g the lower rank comes second and is inserted before
  // (a window of 0 still admits the newest stamp).
  CHECK(h.add(1000, 1, Sight{0, 4.9, 0.0}, apply) == decltype(h)::Outcome::applied);
  MeasurementHistory<State, Input> g(0, initial_state());
  g.add(1000, 1, Sight{0, 4.9, 0.0}, apply);
  CHECK(g.add(1000, 0, Increment{SE2(0.1, 0, 0), Eigen::Matrix3d::Identity() * 1e-6}, apply) ==
        decltype(g)::Outcome::reapplied);
  CHECK((g.state().ekf.state() - h.state().ekf.state()).cwiseAbs().maxCoeff() == 0.0);
  using History = MeasurementHistory<State, Input>;
  CHECK_THROWS_AS(History(-1, initial_state()), std::invalid_argument);
}

#pragma once
// The simulated front end behind `sextant matcher`: answers match requests (match_request_t, from the smoother's
// loop proposals) from ground truth, as a camera front end with a known error model would.  No LCM here: the CLI
// (cli/matcher.cpp) decodes requests and publishes the answers.
//
// For a request to match keyframe a (the new one, at utime_a) against keyframe b (earlier, at utime_b; of body
// source_b when the request is an inter-robot one, and then the answer is a loop from source_b to source):
//  - a request of a body with no truth, or invalid (utime_a or utime_b <= 0, or utime_a == utime_b: the codec
//    refuses such a loop closure) is counted in `invalid` and not answered; a request with utime_a or utime_b outside the truth's
//    time span is counted in `out_of_span` and not answered (no draw is made for either);
//  - otherwise one uniform draw u decides: u < failure_rate: no answer (`failed`); u < failure_rate + wrong_rate:
//    a wrong answer (`wrong`); else the correct answer (`answered`);
//  - the correct answer is a loop_closure_t from b to a (utime_from = utime_b, utime_to = utime_a, keyframe ids
//    and request_id copied): relative = T_b^-1 T_a * Exp(eta), eta ~ N(0, Sigma),
//    Sigma = diag(sigma_t^2 x3, sigma_r^2 x3), information = Sigma^-1, with T_b, T_a the interpolated truth;
//  - a wrong answer has the same form, noise and information, but its relative pose is T_w^-1 T_a * Exp(eta),
//    with T_w the truth at a wrong time t_w drawn uniformly over the truth's span: the pose of a place the body
//    really passed, as when the matcher mistakes b for a similar-looking place.  t_w is redrawn (up to 16 times)
//    until the answer is off by at least `wrong_min_translation` metres or `wrong_min_rotation` radians from the
//    true relative pose; if no draw is (a body that barely moves), the true relative pose is displaced by
//    exactly 2 wrong_min_translation in a random direction (horizontal when planar) and rotated by
//    2 wrong_min_rotation about z.  Wrong answers are indistinguishable from correct ones on the wire.
//  - Planar bodies (the convention of the simulator and of planar odometry): the relative pose is that of the
//    planar parts, SE2(T_b)^-1 SE2(T_a) * Exp(eta) with eta ~ N(0, diag(sigma_t^2, sigma_t^2, sigma_r^2)) over
//    [x, y, yaw], written with planar = true and information nonzero only at x, y and yaw (indices 0, 1, 5).
//  - The answer's utime is the request's utime (the body's clock: the matcher has no other clock consistent with
//    a replayed log; utime_a when the request's is not positive), matcher = options.name, score = 1.
// Deterministic for a seed: one std::mt19937_64 consumed in request order through estimators/random's portable
// draws, so the same seed and the same request sequence give the same answers on every platform.
#include "daemon/engine/events.hpp"
#include "daemon/engine/outputs.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/lie/se2.hpp"
#include "eval/interpolated_trajectory.hpp"

#include <cstdint>
#include <map>
#include <optional>
#include <random>
#include <string>

namespace sextant::tools {

struct SimulatedMatcherOptions {
  double sigma_t = 0.05;      // m, standard deviation of each translation component of the noise
  double sigma_r = 0.01;      // rad, of each rotation component
  double failure_rate = 0.0;  // fraction of requests not answered
  double wrong_rate = 0.0;    // fraction of requests answered wrongly (failure_rate + wrong_rate <= 1)
  uint64_t seed = 1;
  double wrong_min_translation = 1.0;    // m: a wrong answer is at least this far off the truth ...
  double wrong_min_rotation = 0.5;       // rad: ... or at least this much rotated
  std::string name = "sextant-matcher";  // loop_closure_t.matcher
};

/// Ground truth of one body for the matcher.
struct MatcherTruth {
  InterpolatedTrajectory trajectory;
  bool planar = false;
};

struct MatcherCounts {
  int64_t requests = 0, answered = 0, failed = 0, wrong = 0, out_of_span = 0, invalid = 0;
};

class SimulatedMatcher {
 public:
  /// `truth` by body name (match_request_t.source).  Throws std::invalid_argument for options out of range
  /// (sigmas finite and > 0, rates in [0, 1] with a sum <= 1, wrong_min_* finite and >= 0).
  SimulatedMatcher(std::map<std::string, MatcherTruth> truth, const SimulatedMatcherOptions& options);

  /// The answer to `request`, or nullopt (failed, out of span or invalid; see counts()).
  std::optional<engine::LoopClosure> answer(const engine::MatchRequest& request);

  /// The noise-free relative pose T_b^-1 T_a between two times of `source` (planar parts when planar), nullopt
  /// when the body is unknown or a time is outside its truth's span.
  std::optional<SE3> true_relative(const std::string& source, int64_t utime_b, int64_t utime_a) const;
  /// The same between two bodies' times (in the truth's common world frame): T_b^-1 T_a.
  std::optional<SE3> true_relative(const std::string& body_b, int64_t utime_b, const std::string& body_a,
                                   int64_t utime_a) const;

  const MatcherCounts& counts() const { return counts_; }
  const SimulatedMatcherOptions& options() const { return options_; }

 private:
  std::map<std::string, MatcherTruth> truth_;
  SimulatedMatcherOptions options_;
  std::mt19937_64 rng_;
  MatcherCounts counts_;
};

/// Reads the robot ground truth of an LCM log (GROUND_TRUTH channel, truth_t with kind "robot"), one trajectory
/// per truth_t.source.  A body is planar when its odometry in the same log (ODOMETRY, odometry_t.planar) says so;
/// without odometry of that body, when every truth pose has z = 0 and a rotation about z only (within 1e-9).
/// Throws std::runtime_error naming the log when it holds no robot truth.  What the checked reader skipped goes
/// into `damage` when given (the caller reports it).
std::map<std::string, MatcherTruth> read_matcher_truth(const std::string& log_path,
                                                       runtime::LogDamage* damage = nullptr);

}  // namespace sextant::tools

#include "sim/simulated_matcher.hpp"

#include "daemon/runtime/lcm_log.hpp"
#include "estimators/random/portable_random.hpp"

#include <sextant/odometry_t.hpp>
#include <sextant/truth_t.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace sextant::tools {
namespace {

bool finite_nonnegative(double x) { return std::isfinite(x) && x >= 0; }

}  // namespace

SimulatedMatcher::SimulatedMatcher(std::map<std::string, MatcherTruth> truth, const SimulatedMatcherOptions& o)
    : truth_(std::move(truth)), options_(o), rng_(o.seed) {
  std::ostringstream why;
  if (!(std::isfinite(o.sigma_t) && o.sigma_t > 0 && std::isfinite(o.sigma_r) && o.sigma_r > 0))
    why << "simulated matcher: sigma_t and sigma_r must be finite and > 0, got " << o.sigma_t << ", " << o.sigma_r;
  else if (!(finite_nonnegative(o.failure_rate) && finite_nonnegative(o.wrong_rate) &&
             o.failure_rate + o.wrong_rate <= 1))
    why << "simulated matcher: failure_rate and wrong_rate must be in [0, 1] with a sum <= 1, got " << o.failure_rate
        << ", " << o.wrong_rate;
  else if (!(finite_nonnegative(o.wrong_min_translation) && finite_nonnegative(o.wrong_min_rotation)))
    why << "simulated matcher: wrong_min_translation and wrong_min_rotation must be finite and >= 0";
  if (!why.str().empty()) throw std::invalid_argument(why.str());
}

std::optional<SE3> SimulatedMatcher::true_relative(const std::string& source, int64_t utime_b, int64_t utime_a) const {
  return true_relative(source, utime_b, source, utime_a);
}

std::optional<SE3> SimulatedMatcher::true_relative(const std::string& body_b, int64_t utime_b,
                                                   const std::string& body_a, int64_t utime_a) const {
  const auto b = truth_.find(body_b), a = truth_.find(body_a);
  if (b == truth_.end() || a == truth_.end()) return std::nullopt;
  const auto Tb = b->second.trajectory.at(utime_b), Ta = a->second.trajectory.at(utime_a);
  if (!Tb || !Ta) return std::nullopt;
  if (a->second.planar) return SE2::from_se3(*Tb).between(SE2::from_se3(*Ta)).to_se3();
  return Tb->between(*Ta);
}

std::optional<engine::LoopClosure> SimulatedMatcher::answer(const engine::MatchRequest& r) {
  ++counts_.requests;
  // Keyframe b may be another body's (an inter-robot request): the answer is a loop from b's body to a's.
  const std::string& body_b = r.source_b.empty() ? r.source : r.source_b;
  const auto it = truth_.find(body_b);
  if (it == truth_.end() || !truth_.contains(r.source) || r.a.utime <= 0 || r.b.utime <= 0 ||
      (r.a.utime == r.b.utime && body_b == r.source)) {
    ++counts_.invalid;
    return std::nullopt;
  }
  const std::optional<SE3> truth = true_relative(body_b, r.b.utime, r.source, r.a.utime);
  if (!truth) {
    ++counts_.out_of_span;
    return std::nullopt;
  }
  const bool planar = it->second.planar;
  const auto& o = options_;

  const double u = random::uniform01(rng_);
  if (u < o.failure_rate) {
    ++counts_.failed;
    return std::nullopt;
  }
  SE3 relative = *truth;
  if (u < o.failure_rate + o.wrong_rate) {
    ++counts_.wrong;
    const InterpolatedTrajectory& track = it->second.trajectory;
    const auto far_enough = [&](const SE3& x) {
      const SE3 d = truth->between(x);
      return d.translation().norm() >= o.wrong_min_translation || d.rotation().log().norm() >= o.wrong_min_rotation;
    };
    bool found = false;
    const auto span = static_cast<uint64_t>(track.last_utime() - track.first_utime()) + 1;
    for (int attempt = 0; attempt < 16 && !found; ++attempt) {
      const int64_t tw = track.first_utime() + static_cast<int64_t>(random::uniform_index(rng_, span));
      const auto wrong = true_relative(body_b, tw, r.source, r.a.utime);  // T_w^-1 T_a: a matched against place w
      if (wrong && far_enough(*wrong)) relative = *wrong, found = true;
    }
    if (!found) {
      Eigen::Vector3d dir(random::standard_normal(rng_), random::standard_normal(rng_),
                          planar ? 0.0 : random::standard_normal(rng_));
      if (!(dir.norm() > 1e-12)) dir = Eigen::Vector3d::UnitX();
      Vector6d xi = Vector6d::Zero();
      xi.head<3>() = 2 * o.wrong_min_translation * dir.normalized();
      xi[5] = 2 * o.wrong_min_rotation;
      relative = *truth * SE3(SO3::exp(xi.tail<3>()), xi.head<3>());
    }
  } else {
    ++counts_.answered;
  }

  engine::LoopClosure lc;
  lc.information = engine::Matrix6::Zero();
  if (planar) {
    const Eigen::Vector3d eta(o.sigma_t * random::standard_normal(rng_), o.sigma_t * random::standard_normal(rng_),
                              o.sigma_r * random::standard_normal(rng_));
    relative = (SE2::from_se3(relative) * SE2::exp(eta)).to_se3();
    for (int i : {0, 1}) lc.information(i, i) = 1 / (o.sigma_t * o.sigma_t);
    lc.information(5, 5) = 1 / (o.sigma_r * o.sigma_r);
  } else {
    Vector6d eta;
    for (int i = 0; i < 6; ++i) eta[i] = (i < 3 ? o.sigma_t : o.sigma_r) * random::standard_normal(rng_);
    relative = relative * SE3::exp(eta);
    for (int i = 0; i < 6; ++i) lc.information(i, i) = 1 / std::pow(i < 3 ? o.sigma_t : o.sigma_r, 2);
  }
  lc.utime = r.utime > 0 ? r.utime : r.a.utime;
  lc.source = body_b;
  if (body_b != r.source) lc.source_to = r.source;
  lc.planar = planar;
  lc.utime_from = r.b.utime;
  lc.utime_to = r.a.utime;
  lc.keyframe_from = r.b.id;
  lc.keyframe_to = r.a.id;
  lc.request_id = r.request_id;
  lc.relative.position = relative.translation();
  lc.relative.orientation = relative.rotation().quaternion();
  lc.matcher = o.name;
  lc.score = 1.0;
  return lc;
}

std::map<std::string, MatcherTruth> read_matcher_truth(const std::string& log_path, runtime::LogDamage* damage) {
  std::map<std::string, std::vector<std::pair<int64_t, SE3>>> samples;
  std::map<std::string, bool> odometry_planar;  // the first odometry message of each body
  runtime::LogReader reader(log_path);
  while (auto rec = reader.next()) {
    if (rec->channel == "GROUND_TRUTH") {
      sextant::truth_t t;
      if (!runtime::decode_message(rec->data, t) || t.kind != "robot") continue;
      const Eigen::Quaterniond q(t.orientation[0], t.orientation[1], t.orientation[2], t.orientation[3]);
      if (!(q.norm() > 0.5)) continue;  // not a rotation (zero or non-finite): dropped
      samples[t.source].push_back({t.utime, SE3(q, Eigen::Vector3d(t.position[0], t.position[1], t.position[2]))});
    } else if (rec->channel == "ODOMETRY") {
      sextant::odometry_t m;
      if (runtime::decode_message(rec->data, m)) odometry_planar.emplace(m.source, m.planar);
    }
  }
  if (damage != nullptr) *damage = reader.damage();
  if (samples.empty())
    throw std::runtime_error(log_path + ": no robot ground truth (GROUND_TRUTH, truth_t kind \"robot\")");
  std::map<std::string, MatcherTruth> out;
  for (auto& [source, s] : samples) {
    MatcherTruth& m = out[source];
    m.trajectory = InterpolatedTrajectory(std::move(s));
    if (const auto it = odometry_planar.find(source); it != odometry_planar.end()) {
      m.planar = it->second;
    } else {
      m.planar = true;
      for (const auto& [utime, pose] : m.trajectory.samples()) {
        const auto& q = pose.rotation().quaternion();
        if (std::abs(pose.translation().z()) > 1e-9 || std::abs(q.x()) > 1e-9 || std::abs(q.y()) > 1e-9) {
          m.planar = false;
          break;
        }
      }
    }
  }
  return out;
}

}  // namespace sextant::tools

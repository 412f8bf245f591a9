#include "estimators/keyframe/keyframe_selector.hpp"

#include "estimators/lie/lie_archive.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace sextant {
namespace {

bool finite(const SE3& x) { return x.translation().allFinite() && x.rotation().quaternion().coeffs().allFinite(); }

}  // namespace

const char* to_string(KeyframeDecision d) {
  switch (d) {
    case KeyframeDecision::kTooClose:
      return "too_close";
    case KeyframeDecision::kKeyframe:
      return "keyframe";
    case KeyframeDecision::kImplausible:
      return "implausible";
    case KeyframeDecision::kReanchored:
      return "reanchored";
  }
  return "unknown";
}

KeyframeSelector::KeyframeSelector(const KeyframeSelectorOptions& o) : options_(o) {
  std::ostringstream why;
  if (!(std::isfinite(o.k1) && std::isfinite(o.k2) && 0 <= o.k1 && o.k1 < o.k2))
    why << "keyframe selector: need 0 <= k1 < k2 (finite), got k1 = " << o.k1 << ", k2 = " << o.k2;
  else if (!(std::isfinite(o.translation_weight) && o.translation_weight >= 0))
    why << "keyframe selector: translation_weight must be finite and >= 0, got " << o.translation_weight;
  else if (!(std::isfinite(o.rotation_weight) && o.rotation_weight >= 0))
    why << "keyframe selector: rotation_weight must be finite and >= 0, got " << o.rotation_weight;
  else if (o.translation_weight == 0 && o.rotation_weight == 0)
    why << "keyframe selector: translation_weight and rotation_weight are both 0 (every motion would measure 0)";
  else if (o.reanchor_after < 0)
    why << "keyframe selector: reanchor_after must be >= 0, got " << o.reanchor_after;
  if (!why.str().empty()) throw std::invalid_argument(why.str());
}

double KeyframeSelector::magnitude(const SE3& from, const SE3& to) const {
  double t2 = 0, r2 = 0;
  if (options_.planar) {
    const Eigen::Vector3d mu = SE2::from_se3(from).between(SE2::from_se3(to)).log();
    t2 = mu.head<2>().squaredNorm();
    r2 = mu[2] * mu[2];
  } else {
    const Vector6d mu = from.between(to).log();
    t2 = mu.head<3>().squaredNorm();
    r2 = mu.tail<3>().squaredNorm();
  }
  return std::sqrt(options_.translation_weight * t2 + options_.rotation_weight * r2);
}

void KeyframeSelector::reset_reference(const std::optional<SE3>& pose) {
  if (pose && !finite(*pose)) throw std::invalid_argument("keyframe selector: reset_reference to a non-finite pose");
  reference_ = pose;
  jump_run_ = 0;
  jump_last_.reset();
}

KeyframeDecision KeyframeSelector::decide(const SE3& pose) {
  if (!finite(pose)) {
    last_magnitude_ = std::numeric_limits<double>::quiet_NaN();
    ++rejected_;
    jump_run_ = 0;
    jump_last_.reset();
    return KeyframeDecision::kImplausible;
  }
  if (!reference_) {
    last_magnitude_ = 0;
    reference_ = pose;
    ++accepted_;
    return KeyframeDecision::kKeyframe;
  }
  last_magnitude_ = magnitude(*reference_, pose);
  if (!std::isfinite(last_magnitude_) || last_magnitude_ > options_.k2) {
    // A run continues while each implausible pose is a plausible step from the one before it.
    const bool continues = jump_last_ && magnitude(*jump_last_, pose) <= options_.k2;
    jump_run_ = continues ? jump_run_ + 1 : 1;
    jump_last_ = pose;
    if (options_.reanchor_after > 0 && jump_run_ >= options_.reanchor_after) {
      reference_ = pose;
      jump_run_ = 0;
      jump_last_.reset();
      ++reanchored_;
      return KeyframeDecision::kReanchored;
    }
    ++rejected_;
    return KeyframeDecision::kImplausible;
  }
  jump_run_ = 0;
  jump_last_.reset();
  if (last_magnitude_ < options_.k1) {
    ++too_close_;
    return KeyframeDecision::kTooClose;
  }
  reference_ = pose;
  ++accepted_;
  return KeyframeDecision::kKeyframe;
}

void KeyframeSelector::save(archive::ArchiveWriter& w) const {
  w(reference_)(jump_last_)(jump_run_)(last_magnitude_)(accepted_)(rejected_)(too_close_)(reanchored_);
}

void KeyframeSelector::load(archive::ArchiveReader& r) {
  r(reference_)(jump_last_)(jump_run_)(last_magnitude_)(accepted_)(rejected_)(too_close_)(reanchored_);
}

}  // namespace sextant

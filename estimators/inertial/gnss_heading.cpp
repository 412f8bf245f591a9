#include "estimators/inertial/gnss_heading.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sextant::inertial {

void check_options(const GnssHeadingOptions& o) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v))
      throw std::invalid_argument(std::string("gnss heading: ") + name + " must be positive and finite");
  };
  positive(o.baseline_m, "baseline_m");
  positive(o.track_sigma, "track_sigma");
  positive(o.inlier_chi2, "inlier_chi2");
  if (o.min_fixes < 2) throw std::invalid_argument("gnss heading: min_fixes must be at least 2");
  if (o.max_fixes < o.min_fixes) throw std::invalid_argument("gnss heading: max_fixes must be at least min_fixes");
  if (o.max_anchors < 2) throw std::invalid_argument("gnss heading: max_anchors must be at least 2");
  if (!(o.min_inlier_fraction > 0 && o.min_inlier_fraction <= 1))
    throw std::invalid_argument("gnss heading: min_inlier_fraction must be in (0, 1]");
}

Eigen::Matrix2d PlanarAlignment::rotation() const {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return (Eigen::Matrix2d() << c, -s, s, c).finished();
}

Eigen::Vector2d PlanarAlignment::apply(const Eigen::Vector2d& track) const { return rotation() * track + translation; }

Eigen::Matrix2d PlanarAlignment::covariance_at(const Eigen::Vector2d& track) const {
  const Eigen::Vector2d lever = rotation() * (track - track_centroid);
  const Eigen::Vector2d d_dyaw(-lever.y(), lever.x());  // d(Rz(yaw) lever) / d yaw
  return centroid_variance * Eigen::Matrix2d::Identity() + yaw_sigma * yaw_sigma * d_dyaw * d_dyaw.transpose();
}

GnssHeadingAlignment::GnssHeadingAlignment(const GnssHeadingOptions& options) : o_(options) { check_options(o_); }

void GnssHeadingAlignment::reset() {
  pairs_.clear();
  found_.reset();
}

std::optional<PlanarAlignment> GnssHeadingAlignment::add(const Eigen::Vector2d& track, const Eigen::Vector2d& fix,
                                                         const Eigen::Matrix2d& covariance) {
  if (found_) return found_;
  if (!track.allFinite() || !fix.allFinite() || !covariance.allFinite()) return std::nullopt;
  const double fix_variance =
      std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(covariance).eigenvalues().mean());
  pairs_.push_back({track, fix, 1.0 / (fix_variance + o_.track_sigma * o_.track_sigma)});
  while (pairs_.size() > static_cast<size_t>(o_.max_fixes)) pairs_.pop_front();
  found_ = estimate();
  return found_;
}

std::optional<PlanarAlignment> GnssHeadingAlignment::fit(const std::deque<Pair>& pairs, const std::vector<bool>& use) {
  double sw = 0;
  Eigen::Vector2d a = Eigen::Vector2d::Zero(), b = Eigen::Vector2d::Zero();
  int n = 0;
  for (size_t k = 0; k < pairs.size(); ++k)
    if (use[k]) sw += pairs[k].weight, a += pairs[k].weight * pairs[k].track, b += pairs[k].weight * pairs[k].fix, ++n;
  if (n < 2) return std::nullopt;
  a /= sw, b /= sw;
  double cross = 0, dot = 0, spread = 0;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (!use[k]) continue;
    const Eigen::Vector2d p = pairs[k].track - a, q = pairs[k].fix - b;
    const double w = pairs[k].weight;
    cross += w * (p.x() * q.y() - p.y() * q.x()), dot += w * p.dot(q), spread += w * p.squaredNorm();
  }
  if (!(spread > 0)) return std::nullopt;
  PlanarAlignment r;
  r.yaw = std::atan2(cross, dot);
  r.translation = b - r.rotation() * a;
  r.track_centroid = a;
  double chi2 = 0, sq = 0;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (!use[k]) continue;
    const double e2 = (pairs[k].fix - r.apply(pairs[k].track)).squaredNorm();
    chi2 += pairs[k].weight * e2, sq += e2;
  }
  const double s2 = n > 2 ? std::max(1.0, chi2 / (2 * n - 3)) : 1.0;  // 2n residuals, 3 parameters
  r.yaw_sigma = std::sqrt(s2 / spread);
  r.centroid_variance = s2 / sw;
  r.inliers = r.points = n;
  r.rms = std::sqrt(sq / n);
  return r;
}

std::vector<bool> GnssHeadingAlignment::explained(const PlanarAlignment& a) const {
  std::vector<bool> in(pairs_.size());
  for (size_t k = 0; k < pairs_.size(); ++k)
    in[k] = pairs_[k].weight * (pairs_[k].fix - a.apply(pairs_[k].track)).squaredNorm() <= o_.inlier_chi2;
  return in;
}

double GnssHeadingAlignment::span(const std::vector<bool>& use) const {
  double d2 = 0;
  for (size_t i = 0; i < pairs_.size(); ++i)
    for (size_t j = i + 1; j < pairs_.size(); ++j)
      if (use[i] && use[j]) d2 = std::max(d2, (pairs_[i].track - pairs_[j].track).squaredNorm());
  return std::sqrt(d2);
}

std::optional<GnssHeadingAlignment::Candidate> GnssHeadingAlignment::refine(size_t i, size_t j) const {
  const Pair &p = pairs_[i], &q = pairs_[j];
  const Eigen::Vector2d dt = q.track - p.track, df = q.fix - p.fix;
  PlanarAlignment a;
  a.yaw = std::atan2(dt.x() * df.y() - dt.y() * df.x(), dt.dot(df));
  a.translation = (p.fix + q.fix) / 2 - a.rotation() * (p.track + q.track) / 2;
  Candidate c{a, explained(a)};
  for (int iteration = 0; iteration < 3; ++iteration) {
    const auto refit = fit(pairs_, c.inliers);
    if (!refit) return std::nullopt;
    c.alignment = *refit;
    c.inliers = explained(c.alignment);
  }
  c.alignment.inliers = static_cast<int>(std::count(c.inliers.begin(), c.inliers.end(), true));
  c.alignment.points = static_cast<int>(pairs_.size());
  return c;
}

std::optional<PlanarAlignment> GnssHeadingAlignment::estimate() const {
  const size_t n = pairs_.size();
  if (n < static_cast<size_t>(o_.min_fixes) || span(std::vector<bool>(n, true)) < o_.baseline_m) return std::nullopt;
  const size_t anchors = std::min(n, static_cast<size_t>(o_.max_anchors));
  std::optional<Candidate> best;
  for (size_t ai = 0; ai < anchors; ++ai) {
    for (size_t aj = ai + 1; aj < anchors; ++aj) {
      const size_t i = ai * (n - 1) / (anchors - 1), j = aj * (n - 1) / (anchors - 1);
      if ((pairs_[j].track - pairs_[i].track).norm() < o_.baseline_m / 2) continue;
      const auto c = refine(i, j);
      if (!c) continue;
      if (!best || c->alignment.inliers > best->alignment.inliers ||
          (c->alignment.inliers == best->alignment.inliers && c->alignment.rms < best->alignment.rms))
        best = c;
    }
  }
  if (!best || best->alignment.inliers < o_.min_fixes ||
      best->alignment.inliers < o_.min_inlier_fraction * static_cast<double>(n) || span(best->inliers) < o_.baseline_m)
    return std::nullopt;
  return best->alignment;
}

}  // namespace sextant::inertial

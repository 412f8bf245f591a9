#include "eval/trajectory_eval.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <tuple>

namespace sextant::tools {
namespace {

Eigen::Matrix4d matrix_of(const engine::Pose& p) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = p.orientation.normalized().toRotationMatrix();
  m.topRightCorner<3, 1>() = p.position;
  return m;
}

Eigen::Matrix4d inverse_rigid(const Eigen::Matrix4d& m) {
  Eigen::Matrix4d r = Eigen::Matrix4d::Identity();
  r.topLeftCorner<3, 3>() = m.topLeftCorner<3, 3>().transpose();
  r.topRightCorner<3, 1>() = -r.topLeftCorner<3, 3>() * m.topRightCorner<3, 1>();
  return r;
}

// evaluate_rpe.py's find_closest_index: a bisection that keeps the best candidate it visits.
size_t find_closest_index(const std::vector<double>& L, double t) {
  size_t beginning = 0, end = L.size(), best = 0;
  double difference = std::abs(L[0] - t);
  while (beginning < end) {
    const size_t middle = (end + beginning) / 2;
    if (std::abs(L[middle] - t) < difference) {
      difference = std::abs(L[middle] - t);
      best = middle;
    }
    if (t == L[middle]) return middle;
    if (L[middle] > t)
      end = middle;
    else
      beginning = middle + 1;
  }
  return best;
}

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

std::vector<std::pair<size_t, size_t>> associate(const std::vector<StampedPose>& gt,
                                                 const std::vector<StampedPose>& est, double max_difference,
                                                 double offset) {
  // Candidates (|a - (b + offset)|, a, b), sorted like Python sorts the tuples.
  std::vector<std::tuple<double, double, double, size_t, size_t>> cand;
  size_t lo = 0;
  for (size_t j = 0; j < est.size(); ++j) {
    const double b = est[j].t + offset;
    while (lo < gt.size() && gt[lo].t <= b - max_difference) ++lo;
    for (size_t i = lo; i < gt.size() && gt[i].t < b + max_difference; ++i) {
      const double d = std::abs(gt[i].t - b);
      if (d < max_difference) cand.emplace_back(d, gt[i].t, est[j].t, i, j);
    }
  }
  std::sort(cand.begin(), cand.end());
  std::vector<bool> used_gt(gt.size(), false), used_est(est.size(), false);
  std::vector<std::pair<size_t, size_t>> out;
  for (const auto& [d, a, b, i, j] : cand) {
    if (used_gt[i] || used_est[j]) continue;
    used_gt[i] = used_est[j] = true;
    out.emplace_back(i, j);
  }
  std::sort(out.begin(), out.end());
  return out;
}

ErrorStatistics statistics_of(std::vector<double> e) {
  ErrorStatistics s;
  s.count = e.size();
  if (e.empty()) return s;
  const double n = static_cast<double>(e.size());
  double sum = 0, sq = 0;
  for (double x : e) sum += x, sq += x * x;
  s.mean = sum / n;
  s.rmse = std::sqrt(sq / n);
  double var = 0;
  for (double x : e) var += (x - s.mean) * (x - s.mean);
  s.std = std::sqrt(var / n);
  s.min = *std::min_element(e.begin(), e.end());
  s.max = *std::max_element(e.begin(), e.end());
  s.median = median_of(std::move(e));
  return s;
}

AteResult absolute_trajectory_error(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est,
                                    bool estimate_scale, double max_difference) {
  const auto matches = associate(gt, est, max_difference);
  if (matches.size() < 2)
    throw std::invalid_argument("only " + std::to_string(matches.size()) +
                                " pose(s) of the estimate have ground truth within " + std::to_string(max_difference) +
                                " s; at least 2 are needed (are both files in the same time base?)");
  const size_t n = matches.size();
  Eigen::Matrix3Xd model(3, n), data(3, n);
  for (size_t k = 0; k < n; ++k) {
    data.col(static_cast<Eigen::Index>(k)) = gt[matches[k].first].pose.position;
    model.col(static_cast<Eigen::Index>(k)) = est[matches[k].second].pose.position;
  }
  const RigidAlignment a = align_points(model, data, estimate_scale);
  AteResult r;
  r.rotation = a.rotation;
  r.translation = a.translation;
  r.scale = a.scale;
  std::vector<double> errors(n);
  for (size_t k = 0; k < n; ++k)
    errors[k] = (r.scale * r.rotation * model.col(static_cast<Eigen::Index>(k)) + r.translation -
                 data.col(static_cast<Eigen::Index>(k)))
                    .norm();
  r.errors = errors;
  r.stamps.resize(n);
  for (size_t k = 0; k < n; ++k) r.stamps[k] = est[matches[k].second].t;
  r.error = statistics_of(std::move(errors));
  r.matched = n;
  return r;
}

RpeResult relative_pose_error(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est, double delta,
                              DeltaUnit unit, double scale) {
  if (gt.size() < 2 || est.size() < 2) throw std::invalid_argument("RPE needs at least two poses in each trajectory");
  std::vector<double> stamps_est(est.size()), stamps_gt(gt.size());
  for (size_t i = 0; i < est.size(); ++i) stamps_est[i] = est[i].t;
  for (size_t i = 0; i < gt.size(); ++i) stamps_gt[i] = gt[i].t;
  std::vector<double> index(est.size());
  for (size_t i = 0; i < est.size(); ++i)
    index[i] = unit == DeltaUnit::kSeconds ? stamps_est[i] : static_cast<double>(i);
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t i = 0; i < est.size(); ++i) {
    const size_t j = find_closest_index(index, index[i] + delta);
    if (j != est.size() - 1) pairs.emplace_back(i, j);
  }
  std::vector<double> intervals(gt.size() - 1);
  for (size_t i = 1; i < gt.size(); ++i) intervals[i - 1] = stamps_gt[i] - stamps_gt[i - 1];
  const double gt_interval = median_of(intervals);
  std::vector<double> trans, rot, stamps;
  for (const auto& [i, j] : pairs) {
    const size_t g0 = find_closest_index(stamps_gt, stamps_est[i]), g1 = find_closest_index(stamps_gt, stamps_est[j]);
    if (std::abs(stamps_gt[g0] - stamps_est[i]) > 2 * gt_interval ||
        std::abs(stamps_gt[g1] - stamps_est[j]) > 2 * gt_interval)
      continue;
    Eigen::Matrix4d dp = inverse_rigid(matrix_of(est[j].pose)) * matrix_of(est[i].pose);
    dp.topRightCorner<3, 1>() *= scale;
    const Eigen::Matrix4d dq = inverse_rigid(matrix_of(gt[g1].pose)) * matrix_of(gt[g0].pose);
    const Eigen::Matrix4d E = inverse_rigid(dp) * dq;
    trans.push_back(E.topRightCorner<3, 1>().norm());
    const double c = std::clamp((E.topLeftCorner<3, 3>().trace() - 1) / 2, -1.0, 1.0);
    rot.push_back(std::acos(c) * 180.0 / M_PI);
    stamps.push_back(stamps_est[i]);
  }
  if (trans.empty()) throw std::invalid_argument("RPE: no pose pair has ground truth at both ends");
  RpeResult r;
  r.pairs = trans.size();
  r.stamps = std::move(stamps);
  r.translation_errors = trans;
  r.rotation_errors_deg = rot;
  r.translation = statistics_of(std::move(trans));
  r.rotation_deg = statistics_of(std::move(rot));
  return r;
}

}  // namespace sextant::tools

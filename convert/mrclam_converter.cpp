#include "convert/mrclam_converter.hpp"

#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/se2.hpp"
#include "eval/trajectory_io.hpp"

#include <sextant/truth_t.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace sextant::tools {
namespace {

// Rows of numbers of a MRCLAM file (4 '#' header lines, fields separated by white space), with their line numbers.
std::vector<std::pair<int, std::vector<double>>> read_rows(const std::string& path, size_t columns) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::vector<std::pair<int, std::vector<double>>> rows;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream s(line);
    std::vector<double> v;
    for (std::string tok; s >> tok;) {
      char* end = nullptr;
      const double x = std::strtod(tok.c_str(), &end);
      if (end == tok.c_str() || *end != '\0' || !std::isfinite(x))
        throw std::runtime_error(path + ":" + std::to_string(number) + ": not a number: '" + tok + "'");
      v.push_back(x);
    }
    if (v.size() != columns)
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected " + std::to_string(columns) +
                               " values, got " + std::to_string(v.size()));
    rows.emplace_back(number, std::move(v));
  }
  return rows;
}

int64_t utime_of(double t) {
  if (!(std::abs(t) <= 9.2e12)) throw std::runtime_error("MRCLAM time " + std::to_string(t) + " s out of range");
  return static_cast<int64_t>(std::llround(t * 1e6));
}

// An integer column (a barcode, a subject number): casting anything else to int is undefined behaviour (a barcode of
// 1e11 silently became landmark 6).
int integer_at(const std::string& path, int line, double v) {
  if (!(v >= -2147483648.0 && v <= 2147483647.0) || v != std::floor(v))
    throw std::runtime_error(path + ":" + std::to_string(line) +
                             ": not an integer in int's range: " + std::to_string(v));
  return static_cast<int>(v);
}

engine::Pose pose_of(const SE2& x) { return {x.to_se3().translation(), x.to_se3().rotation().quaternion()}; }

}  // namespace

namespace {

// One robot's conversion: its files read, then the ground truth, the odometry and the landmark sightings turned
// into messages, written to the log in time order (truth before odometry before landmarks at the same time).
class MrclamConverter {
 public:
  MrclamConverter(const std::string& dir, int robot, const MrclamOptions& o)
      : dir_(dir),
        r_(dir + "/Robot" + std::to_string(robot)),
        source_("robot" + std::to_string(robot)),
        o_(o),
        barcodes_(read_rows(dir + "/Barcodes.dat", 2)),
        landmarks_(read_rows(dir + "/Landmark_Groundtruth.dat", 5)),
        truth_(read_rows(r_ + "_Groundtruth.dat", 4)),
        odometry_(read_rows(r_ + "_Odometry.dat", 3)),
        measurements_(read_rows(r_ + "_Measurement.dat", 4)) {
    if (truth_.empty() || odometry_.size() < 2) throw std::runtime_error(r_ + ": no ground truth or odometry rows");
    for (const auto& [line, v] : barcodes_)
      subject_of_barcode_[integer_at(dir + "/Barcodes.dat", line, v[1])] =
          integer_at(dir + "/Barcodes.dat", line, v[0]);
  }

  MrclamConversion convert(const std::string& out_lcm, const std::string& gt_tum) {
    add_truth();
    add_odometry();
    add_sightings();
    std::stable_sort(records_.begin(), records_.end(), [](const Record& a, const Record& b) {
      return std::tie(a.utime, a.order) < std::tie(b.utime, b.order);
    });
    runtime::LogWriter out(out_lcm);
    for (const auto& rec : records_) out.write_raw(rec.utime, rec.channel, rec.bytes.data(), rec.bytes.size());
    out.flush();
    if (!gt_tum.empty()) write_tum(gt_tum, gt_);
    return result_;
  }

 private:
  struct Record {
    int64_t utime;
    int order;  // truth before odometry before landmarks at the same time
    std::string channel;
    std::vector<uint8_t> bytes;
  };

  template <class Message>
  void add(int64_t utime, int order, const std::string& channel, const Message& msg) {
    std::vector<uint8_t> b(static_cast<size_t>(msg.getEncodedSize()));
    msg.encode(b.data(), 0, static_cast<int>(b.size()));
    records_.push_back({utime, order, channel, std::move(b)});
  }

  // Ground truth: the robot's poses (also kept for the TUM file) and the landmarks' positions at the first stamp.
  void add_truth() {
    int64_t seq = 0;
    for (const auto& [line, v] : truth_) {
      const SE2 x(v[1], v[2], v[3]);
      gt_.push_back({v[0], pose_of(x)});
      sextant::truth_t t{};
      t.utime = utime_of(v[0]);
      t.sender = "sextant-convert";
      t.seq = seq++;
      t.kind = "robot";
      t.source = source_;
      const auto p = pose_of(x);
      for (int i = 0; i < 3; ++i) t.position[i] = p.position[i];
      t.orientation[0] = p.orientation.w(), t.orientation[1] = p.orientation.x(), t.orientation[2] = p.orientation.y(),
      t.orientation[3] = p.orientation.z();
      add(t.utime, 0, "GROUND_TRUTH", t);
    }
    for (const auto& [line, v] : landmarks_) {
      sextant::truth_t t{};
      t.utime = utime_of(truth_.front().second[0]);
      t.sender = "sextant-convert";
      t.seq = seq++;
      t.kind = "landmark";
      t.id = integer_at(dir_ + "/Landmark_Groundtruth.dat", line, v[0]);
      t.position[0] = v[1], t.position[1] = v[2];
      t.orientation[0] = 1;
      add(t.utime, 0, "GROUND_TRUTH", t);
    }
    result_.truth = seq;
  }

  // Odometry: a command's motion happens `command_delay_s` after its stamp; start from the ground truth nearest the
  // first (delayed) odometry stamp.  Each increment's covariance grows with its distance and turn (at least
  // min_sigma^2), and the pose covariance is composed from them.
  void add_odometry() {
    if (!std::isfinite(o_.command_delay_s)) throw std::runtime_error("MRCLAM command delay is not finite");
    const double delay = o_.command_delay_s;
    const double t_first = odometry_.front().second[0] + delay;
    size_t g = 0;
    while (g + 1 < gt_.size() && std::abs(gt_[g + 1].t - t_first) < std::abs(gt_[g].t - t_first)) ++g;
    pose_ = SE2::from_se3(SE3(gt_[g].pose.orientation, gt_[g].pose.position));
    for (int i : kPlanarAxes) cov_(i, i) = 1e-6;
    engine::Matrix6 q0 = engine::Matrix6::Zero();
    for (int i : kPlanarAxes) q0(i, i) = o_.min_sigma * o_.min_sigma;
    emit_odometry(t_first, q0);
    for (size_t k = 0; k + 1 < odometry_.size(); ++k) {
      const auto& row = odometry_[k].second;
      const double dt = odometry_[k + 1].second[0] - row[0];
      if (dt < 0)
        throw std::runtime_error(r_ + "_Odometry.dat:" + std::to_string(odometry_[k + 1].first) +
                                 ": time goes backwards");
      if (utime_of(odometry_[k + 1].second[0]) == utime_of(row[0])) continue;  // duplicated stamp: nothing elapsed
      const double ds = row[1] * dt, dth = row[2] * dt;
      const SE2 delta = SE2::exp(Eigen::Vector3d(ds, 0, dth));
      const double floor = o_.min_sigma * o_.min_sigma;
      engine::Matrix6 q = engine::Matrix6::Zero();
      q(0, 0) = q(1, 1) = std::max(floor, o_.trans_var_per_metre * std::abs(ds));
      q(5, 5) = std::max(floor, o_.rot_var_per_radian * std::abs(dth) + o_.rot_var_per_metre * std::abs(ds));
      const engine::Matrix6 ad = delta.to_se3().inverse().adjoint();
      cov_ = ad * cov_ * ad.transpose() + q;
      cov_ = (0.5 * (cov_ + cov_.transpose())).eval();
      pose_ = pose_ * delta;
      emit_odometry(odometry_[k + 1].second[0] + delay, q);
    }
  }

  void emit_odometry(double t, const engine::Matrix6& q) {
    engine::Odometry e;
    e.utime = utime_of(t);
    e.source = source_;
    e.planar = true;
    e.pose = pose_of(pose_);
    e.covariance = cov_;
    e.increment_covariance = q;
    add(e.utime, 1, "ODOMETRY", runtime::to_message(e, "sextant-convert", seq_odo_++));
    ++result_.odometry;
  }

  // Landmark sightings, one message per image (rows sharing a stamp); barcodes of robots and unknown ones counted.
  void add_sightings() {
    int64_t seq = 0;
    for (size_t k = 0; k < measurements_.size();) {
      const double t = measurements_[k].second[0];
      engine::LandmarkSightings s;
      s.utime = utime_of(t);
      s.source = source_;
      s.planar = true;
      for (; k < measurements_.size() && measurements_[k].second[0] == t; ++k) {
        const auto& v = measurements_[k].second;
        const auto it = subject_of_barcode_.find(integer_at(r_ + "_Measurement.dat", measurements_[k].first, v[1]));
        if (it == subject_of_barcode_.end()) {
          ++result_.unknown_barcodes;
          continue;
        }
        if (it->second <= 5) {
          ++result_.robot_sightings;
          continue;
        }
        engine::LandmarkObservation ob;
        ob.id = it->second;
        ob.range = v[2];
        ob.azimuth = v[3];
        const double range_sigma = o_.range_sigma_per_metre * ob.range;
        ob.covariance = Eigen::Vector3d(range_sigma * range_sigma, o_.bearing_sigma * o_.bearing_sigma, 0).asDiagonal();
        s.observations.push_back(ob);
      }
      if (s.observations.empty()) continue;
      result_.landmark_observations += static_cast<int64_t>(s.observations.size());
      ++result_.landmark_messages;
      add(s.utime, 2, "LANDMARKS", runtime::to_message(s, "sextant-convert", seq++));
    }
  }

  using Rows = std::vector<std::pair<int, std::vector<double>>>;
  const std::string dir_, r_, source_;
  const MrclamOptions& o_;
  const Rows barcodes_, landmarks_, truth_, odometry_, measurements_;
  std::map<int, int> subject_of_barcode_;
  std::vector<Record> records_;
  MrclamConversion result_;
  std::vector<StampedPose> gt_;
  SE2 pose_;                                       // the odometry's pose
  engine::Matrix6 cov_ = engine::Matrix6::Zero();  // and its covariance
  int64_t seq_odo_ = 0;
};

}  // namespace

MrclamConversion convert_mrclam(const std::string& dir, int robot, const std::string& out_lcm,
                                const std::string& gt_tum, const MrclamOptions& o) {
  if (robot < 1 || robot > 5)
    throw std::runtime_error("MRCLAM robots are numbered 1 to 5, not " + std::to_string(robot));
  return MrclamConverter(dir, robot, o).convert(out_lcm, gt_tum);
}

}  // namespace sextant::tools

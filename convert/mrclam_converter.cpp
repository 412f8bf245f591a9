#include "convert/mrclam_converter.hpp"

#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/se2.hpp"
#include "eval/trajectory_io.hpp"

#include <sextant/truth_t.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <set>
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

// One message of the log being written, ordered by time (truth before odometry before landmarks at the same time;
// then by robot, the order of the merge).
struct Record {
  int64_t utime;
  int order;
  std::string channel;
  std::vector<uint8_t> bytes;
};

// How a robot is converted: alone (odometry on the truth, robot sightings left out) or as one robot of a fleet log.
struct RobotMode {
  bool fleet = false;
  std::set<int> robots_in_log;  // fleet: the robots whose sightings are kept
  bool landmark_truth = true;   // write the landmarks' truth_t (once per log)
};

// One robot's conversion: its files read, then the ground truth, the odometry and the landmark sightings turned
// into records.
class MrclamConverter {
 public:
  MrclamConverter(const std::string& dir, int robot, const MrclamOptions& o, RobotMode mode)
      : dir_(dir),
        r_(dir + "/Robot" + std::to_string(robot)),
        source_("robot" + std::to_string(robot)),
        sender_(mode.fleet ? "sextant-convert-" + source_ : "sextant-convert"),
        o_(o),
        mode_(std::move(mode)),
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

  /// Converts the robot's files; its messages are appended to `records`.
  MrclamConversion add_to(std::vector<Record>& records) {
    records_ = &records;
    add_truth();
    add_odometry();
    add_sightings();
    records_ = nullptr;
    return result_;
  }

  /// The robot's Vicon poses (after add_to).
  const std::vector<StampedPose>& ground_truth() const { return gt_; }
  /// The landmarks' surveyed positions: (subject id, x, y), metres.
  std::vector<std::tuple<int, double, double>> landmark_truth() const {
    std::vector<std::tuple<int, double, double>> out;
    for (const auto& [line, v] : landmarks_)
      out.emplace_back(integer_at(dir_ + "/Landmark_Groundtruth.dat", line, v[0]), v[1], v[2]);
    return out;
  }

 private:
  template <class Message>
  void add(int64_t utime, int order, const std::string& channel, const Message& msg) {
    std::vector<uint8_t> b(static_cast<size_t>(msg.getEncodedSize()));
    msg.encode(b.data(), 0, static_cast<int>(b.size()));
    records_->push_back({utime, order, channel, std::move(b)});
  }

  void add_truth_message(int64_t utime, const std::string& kind, int64_t id, const engine::Pose& p) {
    sextant::truth_t t{};
    t.utime = utime;
    t.sender = sender_;
    t.seq = result_.truth++;
    t.kind = kind;
    t.source = kind == "robot" ? source_ : "";
    t.id = id;
    for (int i = 0; i < 3; ++i) t.position[i] = p.position[i];
    t.orientation[0] = p.orientation.w(), t.orientation[1] = p.orientation.x(), t.orientation[2] = p.orientation.y(),
    t.orientation[3] = p.orientation.z();
    add(t.utime, 0, "GROUND_TRUTH", t);
  }

  // Ground truth: the robot's poses (also kept for the TUM file) and the landmarks' positions at the first stamp.
  void add_truth() {
    for (const auto& [line, v] : truth_) {
      gt_.push_back({v[0], pose_of(SE2(v[1], v[2], v[3]))});
      add_truth_message(utime_of(v[0]), "robot", 0, gt_.back().pose);
    }
    if (!mode_.landmark_truth) return;
    for (const auto& [id, x, y] : landmark_truth())
      add_truth_message(utime_of(truth_.front().second[0]), "landmark", id, pose_of(SE2(x, y, 0)));
  }

  // Odometry: a command's motion happens `command_delay_s` after its stamp; start from the ground truth nearest the
  // first (delayed) odometry stamp, or in a fleet at the identity.  Each increment's covariance grows with its
  // distance and turn (at least min_sigma^2), and the pose covariance is composed from them.
  void add_odometry() {
    if (!std::isfinite(o_.command_delay_s)) throw std::runtime_error("MRCLAM command delay is not finite");
    const double delay = o_.command_delay_s;
    const double t_first = odometry_.front().second[0] + delay;
    size_t g = 0;
    while (g + 1 < gt_.size() && std::abs(gt_[g + 1].t - t_first) < std::abs(gt_[g].t - t_first)) ++g;
    pose_ = mode_.fleet ? SE2() : SE2::from_se3(SE3(gt_[g].pose.orientation, gt_[g].pose.position));
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
    add(e.utime, 1, "ODOMETRY", runtime::to_message(e, sender_, seq_odo_++));
    ++result_.odometry;
  }

  // The subject id a sighting row is written with, or nullopt (counted) for an unknown barcode, and for a robot
  // outside a fleet log.
  std::optional<int> subject_of(size_t k) {
    const auto& v = measurements_[k].second;
    const auto it = subject_of_barcode_.find(integer_at(r_ + "_Measurement.dat", measurements_[k].first, v[1]));
    if (it == subject_of_barcode_.end()) {
      ++result_.unknown_barcodes;
      return std::nullopt;
    }
    if (it->second > 5) return it->second;
    ++result_.robot_sightings;
    if (!mode_.fleet || !mode_.robots_in_log.count(it->second)) return std::nullopt;
    ++result_.robot_sightings_kept;
    return it->second;
  }

  // Landmark (and in a fleet, robot) sightings, one message per image (rows sharing a stamp).
  void add_sightings() {
    int64_t seq = 0;
    for (size_t k = 0; k < measurements_.size();) {
      const double t = measurements_[k].second[0];
      engine::LandmarkSightings s;
      s.utime = utime_of(t);
      s.source = source_;
      s.planar = true;
      for (; k < measurements_.size() && measurements_[k].second[0] == t; ++k) {
        const auto subject = subject_of(k);
        if (!subject) continue;
        const auto& v = measurements_[k].second;
        engine::LandmarkObservation ob;
        ob.id = *subject;
        ob.range = v[2];
        ob.azimuth = v[3];
        const double range_sigma = o_.range_sigma_per_metre * ob.range;
        ob.covariance = Eigen::Vector3d(range_sigma * range_sigma, o_.bearing_sigma * o_.bearing_sigma, 0).asDiagonal();
        s.observations.push_back(ob);
        result_.landmark_observations += *subject > 5;
      }
      if (s.observations.empty()) continue;
      ++result_.landmark_messages;
      add(s.utime, 2, "LANDMARKS", runtime::to_message(s, sender_, seq++));
    }
  }

  using Rows = std::vector<std::pair<int, std::vector<double>>>;
  const std::string dir_, r_, source_, sender_;
  const MrclamOptions& o_;
  const RobotMode mode_;
  const Rows barcodes_, landmarks_, truth_, odometry_, measurements_;
  std::map<int, int> subject_of_barcode_;
  std::vector<Record>* records_ = nullptr;
  MrclamConversion result_;
  std::vector<StampedPose> gt_;
  SE2 pose_;                                       // the odometry's pose
  engine::Matrix6 cov_ = engine::Matrix6::Zero();  // and its covariance
  int64_t seq_odo_ = 0;
};

void check_robot(int robot) {
  if (robot < 1 || robot > 5)
    throw std::runtime_error("MRCLAM robots are numbered 1 to 5, not " + std::to_string(robot));
}

// The robots' conversions merged into one log in time order (stable: at one time and order, by robot).
MrclamConversion write_log(std::vector<MrclamConverter>& robots, const std::string& out_lcm) {
  std::vector<Record> records;
  MrclamConversion total;
  for (auto& r : robots) {
    const MrclamConversion c = r.add_to(records);
    total.odometry += c.odometry, total.landmark_messages += c.landmark_messages;
    total.landmark_observations += c.landmark_observations, total.robot_sightings += c.robot_sightings;
    total.robot_sightings_kept += c.robot_sightings_kept, total.unknown_barcodes += c.unknown_barcodes;
    total.truth += c.truth;
  }
  std::stable_sort(records.begin(), records.end(), [](const Record& a, const Record& b) {
    return std::tie(a.utime, a.order) < std::tie(b.utime, b.order);
  });
  runtime::LogWriter out(out_lcm);
  for (const auto& rec : records) out.write_raw(rec.utime, rec.channel, rec.bytes.data(), rec.bytes.size());
  out.flush();
  return total;
}

}  // namespace

MrclamConversion convert_mrclam(const std::string& dir, int robot, const std::string& out_lcm,
                                const std::string& gt_tum, const MrclamOptions& o) {
  check_robot(robot);
  std::vector<MrclamConverter> robots;
  robots.emplace_back(dir, robot, o, RobotMode{});
  const MrclamConversion c = write_log(robots, out_lcm);
  if (!gt_tum.empty()) write_tum(gt_tum, robots.front().ground_truth());
  return c;
}

MrclamConversion convert_mrclam_fleet(const std::string& dir, const std::vector<int>& robot_numbers,
                                      const std::string& out_lcm, const std::string& gt_prefix,
                                      const MrclamOptions& o) {
  if (robot_numbers.empty()) throw std::runtime_error("no MRCLAM robot to convert");
  const std::set<int> in_log(robot_numbers.begin(), robot_numbers.end());
  if (in_log.size() != robot_numbers.size()) throw std::runtime_error("a MRCLAM robot is listed twice");
  std::vector<MrclamConverter> robots;
  robots.reserve(robot_numbers.size());
  for (int n : robot_numbers) {
    check_robot(n);
    robots.emplace_back(dir, n, o, RobotMode{true, in_log, robots.empty()});
  }
  const MrclamConversion c = write_log(robots, out_lcm);
  if (gt_prefix.empty()) return c;
  for (size_t i = 0; i < robots.size(); ++i)
    write_tum(gt_prefix + "robot" + std::to_string(robot_numbers[i]) + ".txt", robots[i].ground_truth());
  LandmarkPositions landmarks;
  for (const auto& [id, x, y] : robots.front().landmark_truth()) landmarks[id] = Eigen::Vector3d(x, y, 0);
  write_landmarks(gt_prefix + "landmarks.txt", landmarks);
  return c;
}

std::vector<int> parse_mrclam_robots(const std::string& list) {
  std::vector<int> out;
  std::istringstream s(list);
  for (std::string item; std::getline(s, item, ',');) {
    int a = 0, b = 0;
    char dash = 0, extra = 0;
    std::istringstream is(item);
    if ((is >> a) && !(is >> dash)) {
      b = a;
    } else if (dash != '-' || !(is >> b) || (is >> extra) || b < a) {
      throw std::invalid_argument("robots '" + list + "': expected a list such as 1-5 or 1,3,5");
    }
    for (int n = a; n <= b; ++n) out.push_back(n);
  }
  const std::set<int> unique(out.begin(), out.end());
  if (out.empty() || unique.size() != out.size() || *unique.begin() < 1 || *unique.rbegin() > 5)
    throw std::invalid_argument("robots '" + list + "': robots 1 to 5, each at most once");
  return out;
}

}  // namespace sextant::tools

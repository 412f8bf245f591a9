#include "eval/trajectory_io.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace sextant::tools {
namespace {
/// The numbers of one whitespace-separated line; throws naming path:line at the first token that is not a finite
/// number.
std::vector<double> finite_numbers(const std::string& line, const std::string& path, int number) {
  std::istringstream fields(line);
  std::vector<double> v;
  std::string tok;
  while (fields >> tok) {
    char* end = nullptr;
    const double x = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0')
      throw std::runtime_error(path + ":" + std::to_string(number) + ": not a number: '" + tok + "'");
    if (!std::isfinite(x))
      throw std::runtime_error(path + ":" + std::to_string(number) + ": value " + std::to_string(v.size() + 1) +
                               " is not finite");
    v.push_back(x);
  }
  return v;
}

bool blank(const std::string& line) { return line.find_first_not_of(" \t\r") == std::string::npos; }
}  // namespace

void write_landmarks(const std::string& path, const LandmarkPositions& landmarks, bool planar) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  std::fprintf(f, planar ? "# id x y (metres)\n" : "# id x y z (metres)\n");
  for (const auto& [id, p] : landmarks)
    if (planar)
      std::fprintf(f, "%lld %.6f %.6f\n", static_cast<long long>(id), p.x(), p.y());
    else
      std::fprintf(f, "%lld %.6f %.6f %.6f\n", static_cast<long long>(id), p.x(), p.y(), p.z());
  if (std::fclose(f) != 0) throw std::runtime_error("cannot write " + path);
}

LandmarkPositions read_landmarks(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path + ": " + std::strerror(errno));
  LandmarkPositions out;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::vector<double> v = finite_numbers(line, path, number);
    const std::string where = path + ":" + std::to_string(number);
    if (v.size() != 3 && v.size() != 4) throw std::runtime_error(where + ": expected id x y [z]");
    if (v[0] != std::floor(v[0]) || std::abs(v[0]) > 9e15) throw std::runtime_error(where + ": id is not an integer");
    if (!out.emplace(static_cast<int64_t>(v[0]), Eigen::Vector3d(v[1], v[2], v.size() == 4 ? v[3] : 0.0)).second)
      throw std::runtime_error(where + ": landmark " + std::to_string(static_cast<int64_t>(v[0])) + " repeated");
  }
  return out;
}

std::vector<StampedPose> read_tum(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path + ": " + std::strerror(errno));
  std::map<double, engine::Pose> rows;  // later rows with the same stamp win, as in the TUM tools
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    for (char& c : line)
      if (c == ',' || c == '\t' || c == '\r') c = ' ';
    const size_t first = line.find_first_not_of(' ');
    if (first == std::string::npos || line[first] == '#') continue;
    const std::vector<double> v = finite_numbers(line, path, number);
    if (v.size() < 8)
      throw std::runtime_error(path + ":" + std::to_string(number) +
                               ": expected 8 values (t tx ty tz qx qy qz qw), got " + std::to_string(v.size()));
    // Stamps become int64 microseconds: beyond +-9.2e12 s they cannot.
    if (std::abs(v[0]) > 9.2e12)
      throw std::runtime_error(path + ":" + std::to_string(number) + ": timestamp " + std::to_string(v[0]) +
                               " s out of range (|t| <= 9.2e12 s)");
    engine::Pose p;
    p.position = {v[1], v[2], v[3]};
    p.orientation = Eigen::Quaterniond(v[7], v[4], v[5], v[6]);
    rows[v[0]] = p;
  }
  std::vector<StampedPose> out;
  out.reserve(rows.size());
  for (const auto& [t, p] : rows) out.push_back({t, p});
  return out;
}

std::vector<StampedPose> read_kitti(const std::string& path, const std::string& times_path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path + ": " + std::strerror(errno));
  std::vector<StampedPose> out;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (blank(line)) continue;
    const std::vector<double> v = finite_numbers(line, path, number);
    if (v.size() != 12)
      throw std::runtime_error(path + ":" + std::to_string(number) +
                               ": expected 12 values (the 3x4 matrix [R | t] row-major), got " +
                               std::to_string(v.size()));
    Eigen::Matrix3d R;
    R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    const double orthogonality = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!(orthogonality <= 1e-3) || R.determinant() < 0)
      throw std::runtime_error(path + ":" + std::to_string(number) + ": the 3x3 block is not a rotation (|R'R - I| = " +
                               std::to_string(orthogonality) + ", det " + std::to_string(R.determinant()) + ")");
    StampedPose s;
    s.t = static_cast<double>(out.size());
    s.pose.position = {v[3], v[7], v[11]};
    s.pose.orientation = Eigen::Quaterniond(R).normalized();
    out.push_back(s);
  }
  if (times_path.empty()) return out;
  std::ifstream times(times_path);
  if (!times) throw std::runtime_error("cannot read " + times_path + ": " + std::strerror(errno));
  size_t i = 0;
  number = 0;
  double previous = -std::numeric_limits<double>::infinity();
  while (std::getline(times, line)) {
    ++number;
    if (blank(line)) continue;
    const std::vector<double> v = finite_numbers(line, times_path, number);
    if (v.size() != 1)
      throw std::runtime_error(times_path + ":" + std::to_string(number) + ": expected one time in seconds, got " +
                               std::to_string(v.size()) + " values");
    if (v[0] <= previous || std::abs(v[0]) > 9.2e12)
      throw std::runtime_error(times_path + ":" + std::to_string(number) + ": time " + std::to_string(v[0]) +
                               " s is not after the previous one or out of range (|t| <= 9.2e12 s)");
    if (i == out.size())
      throw std::runtime_error(times_path + ":" + std::to_string(number) + ": more times than the " +
                               std::to_string(out.size()) + " poses of " + path);
    previous = v[0];
    out[i++].t = v[0];
  }
  if (i != out.size())
    throw std::runtime_error(times_path + ": " + std::to_string(i) + " times for the " + std::to_string(out.size()) +
                             " poses of " + path);
  return out;
}

TrajectoryWriter::TrajectoryWriter(const std::string& path, TrajectoryFormat format)
    : file_(std::fopen(path.c_str(), "w")), format_(format), path_(path) {
  if (!file_) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
}

TrajectoryWriter::~TrajectoryWriter() {
  if (file_) std::fclose(file_);
}

void TrajectoryWriter::add(const StampedPose& s) {
  const auto& p = s.pose.position;
  const auto q = s.pose.orientation.normalized();
  switch (format_) {
    case TrajectoryFormat::kTum:
      std::fprintf(file_, "%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", s.t, p.x(), p.y(), p.z(), q.x(), q.y(), q.z(),
                   q.w());
      break;
    case TrajectoryFormat::kKitti: {
      const Eigen::Matrix3d R = q.toRotationMatrix();
      std::fprintf(file_, "%.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e\n", R(0, 0), R(0, 1), R(0, 2),
                   p.x(), R(1, 0), R(1, 1), R(1, 2), p.y(), R(2, 0), R(2, 1), R(2, 2), p.z());
      break;
    }
    case TrajectoryFormat::kG2o: {
      std::fprintf(file_, "VERTEX_SE3:QUAT %lld %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", static_cast<long long>(count_),
                   p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w());
      if (count_ > 0) {
        const Eigen::Isometry3d a = Eigen::Translation3d(previous_.position) * previous_.orientation;
        const Eigen::Isometry3d b = Eigen::Translation3d(s.pose.position) * s.pose.orientation;
        const Eigen::Isometry3d d = a.inverse() * b;
        const Eigen::Quaterniond dq(d.linear());
        std::fprintf(file_, "EDGE_SE3:QUAT %lld %lld %.9f %.9f %.9f %.9f %.9f %.9f %.9f",
                     static_cast<long long>(count_ - 1), static_cast<long long>(count_), d.translation().x(),
                     d.translation().y(), d.translation().z(), dq.x(), dq.y(), dq.z(), dq.w());
        for (int r = 0; r < 6; ++r)
          for (int c = r; c < 6; ++c) std::fprintf(file_, " %g", r == c ? 1.0 : 0.0);
        std::fprintf(file_, "\n");
      }
      previous_ = s.pose;
      break;
    }
  }
  ++count_;
}

void TrajectoryWriter::close() {
  if (file_ && std::fclose(file_) != 0) {
    file_ = nullptr;
    throw std::runtime_error("cannot write " + path_ + ": " + std::strerror(errno));
  }
  file_ = nullptr;
}

namespace {
void write_all(const std::string& path, const std::vector<StampedPose>& poses, TrajectoryFormat format) {
  TrajectoryWriter w(path, format);
  for (const auto& s : poses) w.add(s);
  w.close();
}
}  // namespace

void write_tum(const std::string& path, const std::vector<StampedPose>& poses) {
  write_all(path, poses, TrajectoryFormat::kTum);
}

void write_kitti(const std::string& path, const std::vector<StampedPose>& poses) {
  write_all(path, poses, TrajectoryFormat::kKitti);
}

void write_g2o_trajectory(const std::string& path, const std::vector<StampedPose>& poses) {
  write_all(path, poses, TrajectoryFormat::kG2o);
}

}  // namespace sextant::tools

#include "replay/trajectory_io.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace sextant::replay {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

std::unique_ptr<std::FILE, FileCloser> open_for_writing(const std::string& path) {
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(path.c_str(), "w"));
  if (!f) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  return f;
}

}  // namespace

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
    std::istringstream fields(line);
    std::vector<double> v;
    std::string tok;
    while (fields >> tok) {
      char* end = nullptr;
      const double x = std::strtod(tok.c_str(), &end);
      if (end == tok.c_str() || *end != '\0')
        throw std::runtime_error(path + ":" + std::to_string(number) + ": not a number: '" + tok + "'");
      v.push_back(x);
    }
    if (v.size() < 8)
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected 8 values (t tx ty tz qx qy qz qw), got " +
                               std::to_string(v.size()));
    for (size_t i = 0; i < 8; ++i)
      if (!std::isfinite(v[i]))
        throw std::runtime_error(path + ":" + std::to_string(number) + ": value " + std::to_string(i + 1) + " is not finite");
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

void write_tum(const std::string& path, const std::vector<StampedPose>& poses) {
  auto f = open_for_writing(path);
  for (const auto& s : poses) {
    const auto& p = s.pose.position;
    const auto q = s.pose.orientation.normalized();
    std::fprintf(f.get(), "%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", s.t, p.x(), p.y(), p.z(), q.x(), q.y(), q.z(),
                 q.w());
  }
}

void write_kitti(const std::string& path, const std::vector<StampedPose>& poses) {
  auto f = open_for_writing(path);
  for (const auto& s : poses) {
    const Eigen::Matrix3d R = s.pose.orientation.normalized().toRotationMatrix();
    const auto& t = s.pose.position;
    std::fprintf(f.get(), "%.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e\n", R(0, 0), R(0, 1), R(0, 2),
                 t.x(), R(1, 0), R(1, 1), R(1, 2), t.y(), R(2, 0), R(2, 1), R(2, 2), t.z());
  }
}

void write_g2o_trajectory(const std::string& path, const std::vector<StampedPose>& poses) {
  auto f = open_for_writing(path);
  for (size_t i = 0; i < poses.size(); ++i) {
    const auto& p = poses[i].pose.position;
    const auto q = poses[i].pose.orientation.normalized();
    std::fprintf(f.get(), "VERTEX_SE3:QUAT %zu %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", i, p.x(), p.y(), p.z(), q.x(),
                 q.y(), q.z(), q.w());
  }
  for (size_t i = 1; i < poses.size(); ++i) {
    const Eigen::Isometry3d a = Eigen::Translation3d(poses[i - 1].pose.position) * poses[i - 1].pose.orientation;
    const Eigen::Isometry3d b = Eigen::Translation3d(poses[i].pose.position) * poses[i].pose.orientation;
    const Eigen::Isometry3d d = a.inverse() * b;
    const Eigen::Quaterniond q(d.linear());
    std::fprintf(f.get(), "EDGE_SE3:QUAT %zu %zu %.9f %.9f %.9f %.9f %.9f %.9f %.9f", i - 1, i, d.translation().x(),
                 d.translation().y(), d.translation().z(), q.x(), q.y(), q.z(), q.w());
    for (int r = 0; r < 6; ++r)
      for (int c = r; c < 6; ++c) std::fprintf(f.get(), " %g", r == c ? 1.0 : 0.0);
    std::fprintf(f.get(), "\n");
  }
}

}  // namespace sextant::replay

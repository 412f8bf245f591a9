#include "convert/euroc_converter.hpp"

#include "daemon/runtime/lcm_log.hpp"
#include "estimators/lie/unit_quaternion.hpp"
#include "eval/trajectory_io.hpp"

#include <sextant/imu_t.hpp>
#include <sextant/truth_t.hpp>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace sextant::tools {
namespace {

namespace fs = std::filesystem;

struct Row {
  int64_t ns = 0;
  std::vector<double> values;
  std::string where;  // "FILE:LINE: "
};

// The rows of an ASL CSV file with `columns` numbers after the timestamp, strictly increasing in time.
std::vector<Row> read_asl_csv(const fs::path& path, size_t columns) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::vector<Row> rows;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    const std::string where = path.string() + ":" + std::to_string(n) + ": ";
    Row r;
    r.where = where;
    const char* p = line.c_str();
    char* end = nullptr;
    errno = 0;
    r.ns = std::strtoll(p, &end, 10);
    if (end == p) throw std::runtime_error(where + "no timestamp");
    if (errno == ERANGE) throw std::runtime_error(where + "timestamp out of range");
    for (p = end; *p == ',' || *p == ' '; p = end) {
      ++p;
      const double v = std::strtod(p, &end);
      if (end == p)
        throw std::runtime_error(where + "field " + std::to_string(r.values.size() + 2) + " is not a number");
      if (!std::isfinite(v))
        throw std::runtime_error(where + "field " + std::to_string(r.values.size() + 2) + " is not finite");
      r.values.push_back(v);
    }
    if (*p != '\0')
      throw std::runtime_error(where + "unexpected text after field " + std::to_string(r.values.size() + 1));
    if (r.values.size() != columns)
      throw std::runtime_error(where + std::to_string(r.values.size() + 1) + " fields, expected " +
                               std::to_string(columns + 1));
    if (!rows.empty() && r.ns <= rows.back().ns)
      throw std::runtime_error(where + "timestamp not after the previous row's");
    rows.push_back(std::move(r));
  }
  return rows;
}

fs::path find_first(const fs::path& dir, std::initializer_list<const char*> candidates) {
  for (const fs::path& base : {dir, dir / "mav0"})
    for (const char* c : candidates)
      if (fs::exists(base / c)) return base / c;
  return {};
}

sextant::imu_t imu_message(const Row& r, int64_t seq, double rate_hz, const EurocConversionOptions& o) {
  sextant::imu_t m{};
  m.utime = r.ns / 1000;
  m.sender = "sextant-convert";
  m.seq = seq;
  m.source = o.source;
  m.frame = "imu0";
  m.has_angular_velocity = true;
  m.has_linear_acceleration = true;
  const double vg = o.gyro_noise_density * o.gyro_noise_density * rate_hz;
  const double va = o.accel_noise_density * o.accel_noise_density * rate_hz;
  for (int i = 0; i < 3; ++i) {
    m.angular_velocity[i] = r.values[static_cast<size_t>(i)];
    m.linear_acceleration[i] = r.values[static_cast<size_t>(3 + i)];
    m.angular_velocity_covariance[4 * i] = vg;
    m.linear_acceleration_covariance[4 * i] = va;
  }
  m.orientation[0] = 1;
  return m;
}

sextant::truth_t truth_message(const Row& r, int64_t seq, const std::string& source) {
  sextant::truth_t m{};
  m.utime = r.ns / 1000;
  m.sender = "sextant-convert";
  m.seq = seq;
  m.kind = "robot";
  m.source = source;
  // The CSV's values are finite (read_row); a quaternion of 1e300s or of denormals is still the rotation it spells.
  const auto unit = unit_quaternion(r.values[3], r.values[4], r.values[5], r.values[6]);
  if (!unit) throw std::runtime_error(r.where + "the orientation quaternion is zero");
  const Eigen::Quaterniond& q = *unit;
  for (int i = 0; i < 3; ++i) m.position[i] = r.values[static_cast<size_t>(i)];
  m.orientation[0] = q.w(), m.orientation[1] = q.x(), m.orientation[2] = q.y(), m.orientation[3] = q.z();
  return m;
}

}  // namespace

EurocConversion convert_euroc(const std::string& dir, const std::string& out_lcm, const std::string& gt_tum,
                              const EurocConversionOptions& options) {
  const fs::path imu_path = find_first(dir, {"imu0/data.csv"});
  if (imu_path.empty()) throw std::runtime_error(dir + ": no imu0/data.csv (nor mav0/imu0/data.csv)");
  const std::vector<Row> imu = read_asl_csv(imu_path, 6);
  if (imu.size() < 2) throw std::runtime_error(imu_path.string() + ": fewer than two samples");
  const fs::path gt_path = find_first(dir, {"state_groundtruth_estimate0/data.csv", "gt0/data.csv"});
  const std::vector<Row> gt = gt_path.empty() ? std::vector<Row>{} : read_asl_csv(gt_path, 16);
  // The stamps increase, so their difference fits in 64 unsigned bits (in int64_t it may overflow).
  const double span_s =
      static_cast<double>(static_cast<uint64_t>(imu.back().ns) - static_cast<uint64_t>(imu.front().ns)) * 1e-9;
  const double rate_hz = static_cast<double>(imu.size() - 1) / span_s;

  // Both streams in time order (a merge of two sorted lists; IMU first at equal stamps).
  runtime::LogWriter out(out_lcm);
  EurocConversion result;
  std::vector<StampedPose> truth;
  size_t i = 0, j = 0;
  while (i < imu.size() || j < gt.size()) {
    if (j == gt.size() || (i < imu.size() && imu[i].ns <= gt[j].ns)) {
      const sextant::imu_t m = imu_message(imu[i++], result.imu++, rate_hz, options);
      out.write(m.utime, options.imu_channel, m);
    } else {
      const sextant::truth_t m = truth_message(gt[j++], result.truth++, options.source);
      out.write(m.utime, "GROUND_TRUTH", m);
      StampedPose p;
      p.t = static_cast<double>(m.utime) * 1e-6;
      p.pose.position = Eigen::Vector3d(m.position[0], m.position[1], m.position[2]);
      p.pose.orientation = Eigen::Quaterniond(m.orientation[0], m.orientation[1], m.orientation[2], m.orientation[3]);
      truth.push_back(p);
    }
  }
  out.flush();
  if (!gt_tum.empty()) write_tum(gt_tum, truth);
  return result;
}

}  // namespace sextant::tools

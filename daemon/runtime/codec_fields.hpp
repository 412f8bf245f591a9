#pragma once
// The codec's field copies between lcm-gen's arrays and Eigen (codec.cpp: inputs, codec_outputs.cpp: outputs): one
// home for both directions.  Row-major arrays (as the .lcm files define every matrix), quaternions [w, x, y, z].
#include "daemon/engine/events.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <string>

namespace sextant::runtime::codec_fields {

template <int N>
void copy_row_major(const Eigen::Matrix<double, N, N>& m, double* out) {
  Eigen::Map<Eigen::Matrix<double, N, N, Eigen::RowMajor>> dst(out);
  dst = m;
}

/// A rotation as the messages' quaternion [w, x, y, z], normalized.
inline void copy_quaternion(const Eigen::Quaterniond& orientation, double quat[4]) {
  const Eigen::Quaterniond q = orientation.normalized();
  quat[0] = q.w();
  quat[1] = q.x();
  quat[2] = q.y();
  quat[3] = q.z();
}

inline void copy_pose(const engine::Pose& p, double pos[3], double quat[4]) {
  for (int i = 0; i < 3; ++i) pos[i] = p.position[i];
  copy_quaternion(p.orientation, quat);
}

inline Eigen::Quaterniond read_quaternion(const double quat[4]) {
  return Eigen::Quaterniond(quat[0], quat[1], quat[2], quat[3]);
}

inline engine::Pose read_pose(const double pos[3], const double quat[4]) {
  engine::Pose p;
  p.position = Eigen::Vector3d(pos[0], pos[1], pos[2]);
  p.orientation = read_quaternion(quat);
  return p;
}

template <int N>
Eigen::Matrix<double, N, N> read_matrix(const double* v) {
  return Eigen::Map<const Eigen::Matrix<double, N, N, Eigen::RowMajor>>(v);
}

// Every message starts the same way (lcmtypes/sextant/*.lcm): its time, the sender's name and the sender's sequence number.
template <class Message>
Message message_header(int64_t utime, const std::string& sender, int64_t seq) {
  Message m{};
  m.utime = utime;
  m.sender = sender;
  m.seq = seq;
  return m;
}

}  // namespace sextant::runtime::codec_fields

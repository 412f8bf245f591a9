#pragma once
// Trajectory files: TUM (the TUM RGB-D benchmark's text format), KITTI (3x4 row-major pose per line) and g2o
// (VERTEX_SE3:QUAT lines), for evo, g2o_viewer and scripts.
//
// TUM: one pose per line, "timestamp tx ty tz qx qy qz qw" (seconds, metres, quaternion x y z w).  Reading follows
// the TUM tools (associate.py and evaluate_ate.py of the TUM RGB-D benchmark): commas and tabs count as spaces, empty lines and lines
// starting with '#' are skipped, and a repeated timestamp replaces the earlier row.
#include "daemon/engine/events.hpp"

#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace sextant::tools {

struct StampedPose {
  double t = 0;  // seconds
  engine::Pose pose;
};

/// Reads a TUM file; the result is sorted by time with unique stamps.  Throws std::runtime_error naming the file
/// and line of a malformed row (fewer than 8 numbers, or a number that does not parse).
std::vector<StampedPose> read_tum(const std::string& path);

/// Reads a KITTI odometry pose file: one pose per line, the 12 numbers of the 3x4 matrix [R | t] row-major (the
/// camera-to-world pose of the benchmark's ground truth and of its submissions).  The file has no stamps: with
/// `times_path` (the sequence's times.txt, one time in seconds per line) pose i gets time i of that file, which must
/// have exactly as many lines; without it pose i gets t = i, so two KITTI files associate frame by frame.  Empty lines
/// are skipped.  Throws std::runtime_error naming the file and line of a row that is not 12 finite numbers or whose
/// R is not a rotation (|R'R - I| > 1e-3 or det R < 0: a file of another format fails here instead of reading as
/// nonsense); R is re-orthonormalized through its quaternion.
std::vector<StampedPose> read_kitti(const std::string& path, const std::string& times_path = "");

/// Writes a TUM file (fixed precision: 6 decimals for time, 9 for the rest, so the output is deterministic).
void write_tum(const std::string& path, const std::vector<StampedPose>& poses);

/// Writes a KITTI pose file: the 3x4 matrix [R | t] of each pose, row-major, one pose per line.
void write_kitti(const std::string& path, const std::vector<StampedPose>& poses);

/// Writes the poses as a g2o graph of VERTEX_SE3:QUAT lines (ids 0..n-1), consecutive poses joined by
/// EDGE_SE3:QUAT with identity information, so g2o_viewer shows the path.
void write_g2o_trajectory(const std::string& path, const std::vector<StampedPose>& poses);

/// Landmark positions by id, metres.
using LandmarkPositions = std::map<int64_t, Eigen::Vector3d>;

/// Writes landmark positions, one "id x y" line each ("id x y z" unless `planar`), after a '#' comment line; 6
/// decimals.  Throws std::runtime_error naming the path when it cannot be written.
void write_landmarks(const std::string& path, const LandmarkPositions& landmarks, bool planar = true);

/// Reads a landmark file: "id x y" or "id x y z" per line (z = 0 when absent); '#' lines and empty lines skipped.
/// Throws std::runtime_error naming the file and line of a malformed row (an id that is not an integer, a repeated id).
LandmarkPositions read_landmarks(const std::string& path);

enum class TrajectoryFormat { kTum, kKitti, kG2o };

/// Writes a trajectory file pose by pose, as the poses come (a replay streams its estimate to disk instead of holding
/// it): TUM, KITTI, or g2o (each vertex followed by the edge from the one before).  The same bytes as the functions
/// above for the same poses, except that g2o interleaves vertices and edges.  Throws std::runtime_error naming the
/// path when it cannot be opened or written.
class TrajectoryWriter {
 public:
  TrajectoryWriter(const std::string& path, TrajectoryFormat format);
  ~TrajectoryWriter();
  TrajectoryWriter(const TrajectoryWriter&) = delete;
  TrajectoryWriter& operator=(const TrajectoryWriter&) = delete;
  void add(const StampedPose& pose);
  /// Flushes and closes the file (throws when that fails); the destructor closes it silently.
  void close();
  int64_t count() const { return count_; }

 private:
  std::FILE* file_;
  TrajectoryFormat format_;
  std::string path_;
  int64_t count_ = 0;
  engine::Pose previous_;
};

}  // namespace sextant::tools

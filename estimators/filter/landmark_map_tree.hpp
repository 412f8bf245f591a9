#pragma once
// A persistent (copy-on-write) map from landmark slot 0, 1, 2, ... to a landmark's 2x2 EKF: the landmark maps of
// FastSLAM's particles (Montemerlo, Thrun, Koller & Wegbreit, "FastSLAM: A factored solution to the simultaneous
// localization and mapping problem", AAAI 2002, §4 "Efficient implementation", Fig. 4).
//
// The slots are the leaves of a complete binary tree of depth d (capacity 2^d, grown by adding a root above the old
// one).  Copying a map copies one pointer; `set` copies only the d nodes on the path from the root to the slot
// (path copying), so a resampling step that duplicates a particle shares its whole map, and an update of one
// landmark costs O(log M) time and memory while every other particle that shares the old tree keeps seeing the old
// landmark.  Nodes are immutable once built and reference counted (std::shared_ptr): a subtree lives as long as one
// map uses it.  Not thread-safe for concurrent writers of one map; different maps may share nodes across threads
// (the reference counts are atomic).
#include "estimators/archive/binary_archive.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <memory>

namespace sextant::filter {

/// One landmark of one particle: position and covariance in the map frame (metres, m^2), plus bookkeeping.
struct MapLandmark {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  int64_t id = -1;        // the landmark id reported outside (sighting id, or one given at creation)
  int observations = 0;   // sightings that updated or created it
  int64_t last_seen = 0;  // the owner's count of sighting batches when it was last seen (tentative-landmark rule)
};

class LandmarkMapTree {
 public:
  /// Number of slots ever used (one past the largest slot set); erased slots count.
  int32_t slots() const { return slots_; }
  /// The landmark in `slot`, or nullptr (never set, erased, or out of range).  O(log M).
  const MapLandmark* find(int32_t slot) const;
  /// Stores `landmark` in `slot` (>= 0), copying the root-to-leaf path.  O(log M).
  void set(int32_t slot, const MapLandmark& landmark);
  /// Stores `landmark` in slot `slots()` and returns that slot.
  int32_t push_back(const MapLandmark& landmark);
  /// Empties `slot` (path copying as `set`).
  void erase(int32_t slot);
  /// Calls f(slot, landmark) for every stored landmark, in slot order.  O(M).
  void for_each(const std::function<void(int32_t, const MapLandmark&)>& f) const;

  /// Whether the two maps hold the very same stored object for `slot` (shared, not copied): for tests and
  /// memory accounting.
  bool shares_slot_with(const LandmarkMapTree& other, int32_t slot) const;
  /// Nodes reachable from this map (internal and leaves), counting shared ones once per map.
  int64_t node_count() const;

  /// The stored landmarks by slot and the slot count in the binary archive.  A loaded map holds the same landmarks
  /// in the same slots, in nodes of its own (shared with no other map until copied).
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);

 private:
  struct Node;
  using NodePtr = std::shared_ptr<const Node>;
  struct Node {
    NodePtr child[2];
    std::shared_ptr<const MapLandmark> leaf;  // only at depth_
  };
  static NodePtr with_slot(const NodePtr& node, int depth, int32_t slot, std::shared_ptr<const MapLandmark> leaf);
  const Node* leaf_node(int32_t slot) const;

  NodePtr root_;
  int depth_ = 0;  // capacity 2^depth_
  int32_t slots_ = 0;
};

}  // namespace sextant::filter

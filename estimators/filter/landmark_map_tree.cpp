#include "estimators/filter/landmark_map_tree.hpp"

#include <stdexcept>

namespace sextant::filter {

const LandmarkMapTree::Node* LandmarkMapTree::leaf_node(int32_t slot) const {
  if (slot < 0 || slot >= slots_) return nullptr;
  const Node* n = root_.get();
  for (int level = depth_; n != nullptr && level > 0; --level) n = n->child[(slot >> (level - 1)) & 1].get();
  return n;
}

const MapLandmark* LandmarkMapTree::find(int32_t slot) const {
  const Node* n = leaf_node(slot);
  return n == nullptr ? nullptr : n->leaf.get();
}

LandmarkMapTree::NodePtr LandmarkMapTree::with_slot(const NodePtr& node, int depth, int32_t slot,
                                                    std::shared_ptr<const MapLandmark> leaf) {
  auto copy = std::make_shared<Node>();
  if (depth == 0) {
    copy->leaf = std::move(leaf);
    return copy;
  }
  if (node) *copy = *node;  // shares both children; one is replaced below
  const int bit = (slot >> (depth - 1)) & 1;
  copy->child[bit] = with_slot(copy->child[bit], depth - 1, slot, std::move(leaf));
  return copy;
}

void LandmarkMapTree::set(int32_t slot, const MapLandmark& landmark) {
  if (slot < 0 || slot == INT32_MAX) throw std::out_of_range("LandmarkMapTree::set: slot " + std::to_string(slot));
  while (depth_ < 31 && slot >= (int32_t{1} << depth_)) {  // grow: the old tree becomes the left half
    if (root_) {
      auto up = std::make_shared<Node>();
      up->child[0] = root_;
      root_ = std::move(up);
    }
    ++depth_;
  }
  root_ = with_slot(root_, depth_, slot, std::make_shared<const MapLandmark>(landmark));
  if (slot >= slots_) slots_ = slot + 1;
}

int32_t LandmarkMapTree::push_back(const MapLandmark& landmark) {
  const int32_t slot = slots_;
  set(slot, landmark);
  return slot;
}

void LandmarkMapTree::erase(int32_t slot) {
  if (find(slot) == nullptr) return;
  root_ = with_slot(root_, depth_, slot, nullptr);
}

void LandmarkMapTree::for_each(const std::function<void(int32_t, const MapLandmark&)>& f) const {
  // Depth-first, left to right: slot order.
  const std::function<void(const Node*, int, int32_t)> visit = [&](const Node* n, int level, int32_t prefix) {
    if (n == nullptr) return;
    if (level == 0) {
      if (n->leaf) f(prefix, *n->leaf);
      return;
    }
    visit(n->child[0].get(), level - 1, prefix << 1);
    visit(n->child[1].get(), level - 1, (prefix << 1) | 1);
  };
  visit(root_.get(), depth_, 0);
}

bool LandmarkMapTree::shares_slot_with(const LandmarkMapTree& other, int32_t slot) const {
  const Node* a = leaf_node(slot);
  const Node* b = other.leaf_node(slot);
  return a != nullptr && b != nullptr && a->leaf != nullptr && a->leaf == b->leaf;
}

int64_t LandmarkMapTree::node_count() const {
  const std::function<int64_t(const Node*)> count = [&](const Node* n) -> int64_t {
    return n == nullptr ? 0 : 1 + count(n->child[0].get()) + count(n->child[1].get());
  };
  return count(root_.get());
}

void LandmarkMapTree::save(archive::ArchiveWriter& w) const {
  int64_t n = 0;
  for_each([&](int32_t, const MapLandmark&) { ++n; });
  w(slots_)(n);
  for_each(
      [&](int32_t slot, const MapLandmark& l) { w(slot)(l.mean)(l.covariance)(l.id)(l.observations)(l.last_seen); });
}

void LandmarkMapTree::load(archive::ArchiveReader& r) {
  *this = LandmarkMapTree{};
  const auto slots = r.get<int32_t>();
  const auto n = r.get<int64_t>();
  if (slots < 0 || n < 0 || n > slots || static_cast<uint64_t>(n) > r.remaining() / 64)
    r.fail("a landmark map of bad size");
  for (int64_t k = 0; k < n; ++k) {
    const auto slot = r.get<int32_t>();
    if (slot < 0 || slot >= slots) r.fail("a landmark map slot out of range");
    MapLandmark l;
    r(l.mean)(l.covariance)(l.id)(l.observations)(l.last_seen);
    set(slot, l);
  }
  slots_ = slots;
}

}  // namespace sextant::filter

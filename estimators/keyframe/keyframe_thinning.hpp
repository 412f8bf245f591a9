#pragma once
// Which keyframes a lifelong graph keeps (the reduced pose graph idea of Johannsson, Kaess, Fallon and Leonard,
// "Temporally scalable visual SLAM using a reduced pose graph", ICRA 2013: the graph grows with the explored space,
// not with time):
//   - the newest `window` keyframes, with all their measurements (the part of the map being built now);
//   - the first keyframe (the gauge: the map frame);
//   - of the older ones, one per place: a place is a cell of `cell_size` metres (x, y, and z for 3-D bodies) and a
//     heading sector of `heading_sector` radians, at the keyframe's current estimate; the place's earliest keyframe
//     is kept (the one loops and sightings have referred to longest), the later ones are thinned.
// The result depends only on the keyframes' ids, estimates and the options: the same input keeps the same set.
#include "estimators/lie/se3.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace sextant {

struct KeyframeThinningOptions {
  int window = 1000;                           // newest keyframes always kept (>= 1)
  double cell_size = 1.0;                      // m (> 0)
  double heading_sector = 0.7853981633974483;  // rad (> 0): pi / 4
};

struct ThinningCandidate {
  int64_t id = 0;  // increasing along the list
  SE3 pose;        // current estimate in the map frame
};

/// A place: the cell (x, y, and z for 3-D bodies; 0 for planar ones) and the heading sector of a pose in the map
/// frame.  The heading is the direction the body's x axis points to in the map's horizontal plane.
using KeyframePlace = std::array<int64_t, 4>;
KeyframePlace place_of(const SE3& pose, bool planar, const KeyframeThinningOptions& options);

/// keep[i] for each keyframe of `keyframes` (oldest first).  Throws std::invalid_argument for bad options.
std::vector<char> keyframes_to_keep(const std::vector<ThinningCandidate>& keyframes, bool planar,
                                    const KeyframeThinningOptions& options);

}  // namespace sextant

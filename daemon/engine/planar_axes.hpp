#pragma once
// Planar axes (x, y, yaw) of sextant's 6-D tangent: defined in estimators/lie/planar_axes.hpp (the engine's namespace
// is inside sextant's, so kPlanarAxes, planar_block and embed_planar are found from here unqualified).
#include "daemon/engine/events.hpp"
#include "estimators/lie/planar_axes.hpp"

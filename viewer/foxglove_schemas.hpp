#pragma once
// The Foxglove message schemas sextant's views use, as JSON Schema text: foxglove.PoseInFrame,
// foxglove.FrameTransforms and foxglove.SceneUpdate, from viewer/schemas/ (written for sextant: the fields it sends, named
// and typed as Foxglove's schemas of the same name define them; tests/viewer/ validates every message against both
// these and the reference package's).  Compiled in at build time.
#include <map>
#include <string>

namespace sextant::viewer {

/// Schema name ("foxglove.PoseInFrame") -> its JSON Schema.
const std::map<std::string, std::string>& foxglove_schema_texts();

}  // namespace sextant::viewer

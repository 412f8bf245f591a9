#pragma once
// sextant's version: `git describe` of the checkout it was built from, stamped at build time, or the project
// version (CMakeLists.txt) when built outside git.  Printed by `--version`, sent in every SEXTANT_STATUS and written
// into the replay JSON, so a result can be traced to the code that produced it.

namespace sextant {

/// e.g. "v0.2.0-3-gabc1234", "0.1.0+gb7308dc-dirty" (a checkout without tags and with local changes) or "0.1.0".
const char* version();

}  // namespace sextant

# Writes OUT: a C++ source defining foxglove_schema_texts() from the JSON files in SCHEMA_DIR, each named after its file ("foxglove.PoseInFrame.json" -> "foxglove.PoseInFrame").  Run with cmake -P.
file(GLOB SCHEMAS ${SCHEMA_DIR}/*.json)
set(body "")
foreach(f ${SCHEMAS})
  get_filename_component(name ${f} NAME)
  string(REGEX REPLACE "\\.json$" "" name "${name}")
  file(READ ${f} text)
  string(APPEND body "      {\"${name}\", R\"schema(${text})schema\"},\n")
endforeach()
file(WRITE ${OUT}.tmp "// Generated from viewer/schemas/*.json by viewer/embed_schemas.cmake; do not edit.
#include \"viewer/foxglove_schemas.hpp\"

namespace sextant::viewer {

const std::map<std::string, std::string>& foxglove_schema_texts() {
  static const std::map<std::string, std::string> texts = {
${body}  };
  return texts;
}

}  // namespace sextant::viewer
")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)

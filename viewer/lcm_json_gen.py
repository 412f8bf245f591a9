#!/usr/bin/env python3
"""Generates the JSON form of sextant's LCM messages from their definitions (lcmtypes/sextant/*.lcm).

For every struct it writes, into one C++ source file:
  - a JSON Schema (draft 2020-12 subset: type, properties, required, items, minItems/maxItems, description from the
    field's comment), the nested structs inlined as Foxglove's own schemas are;
  - `to_json(const sextant::T&)`: every field under its own name, in declaration order, counts included;
  - `from_json(json, sextant::T&)`: the inverse, refusing (naming the field path) a missing field, a wrong type, an
    integer out of the field's range, or an array whose length differs from its fixed size or its count field;
  - one entry of the registry (viewer/lcm_json.hpp) keyed by lcm-gen's fingerprint.
The grammar read is the part of LCM's that sextant uses: `package`, `struct`, `const` lines, fields of the primitive
types or of other structs of the package, one-dimensional fixed or variable arrays, `//` comments.  Anything else is
an error naming file:line.

Usage: lcm_json_gen.py OUT.cpp FILE.lcm...
"""
import json
import re
import sys

PRIMITIVES = {
    # lcm type: (C++ type, JSON Schema)
    "int8_t": ("int8_t", {"type": "integer", "minimum": -128, "maximum": 127}),
    "int16_t": ("int16_t", {"type": "integer", "minimum": -32768, "maximum": 32767}),
    "int32_t": ("int32_t", {"type": "integer", "minimum": -2**31, "maximum": 2**31 - 1}),
    "int64_t": ("int64_t", {"type": "integer"}),
    "byte": ("uint8_t", {"type": "integer", "minimum": 0, "maximum": 255}),
    "boolean": ("bool", {"type": "boolean"}),
    "float": ("float", {"type": "number"}),
    "double": ("double", {"type": "number"}),
    "string": ("std::string", {"type": "string"}),
}
FIELD = re.compile(r"^([A-Za-z_][\w.]*)\s+([A-Za-z_]\w*)\s*(?:\[\s*([A-Za-z_]\w*|\d+)\s*\])?\s*;$")


class Struct:
    def __init__(self, name, doc, where):
        self.name, self.doc, self.where, self.fields = name, doc, where, []


def fail(where, what):
    sys.exit(f"{where}: {what}")


def parse(path):
    """The structs of one .lcm file: each with its fields (type, name, dimension, comment)."""
    structs, current, doc = [], None, []
    with open(path) as f:
        lines = f.read().split("\n")
    for n, raw in enumerate(lines, 1):
        where = f"{path}:{n}"
        code, _, comment = raw.partition("//")
        code, comment = code.strip(), comment.strip()
        if not code:
            if comment and current is None:
                doc.append(comment)
            continue
        if code.startswith("package "):
            if code != "package sextant;":
                fail(where, f"package must be sextant: '{code}'")
        elif current is None:
            m = re.match(r"^struct\s+(\w+)$", code)
            if not m:
                fail(where, f"expected 'struct NAME', found '{code}'")
            current, doc = Struct(m.group(1), " ".join(doc), where), []
        elif code == "{":
            continue
        elif code == "}":
            structs.append(current)
            current = None
        elif code.startswith("const "):
            continue  # constants are values of a field, not fields
        else:
            m = FIELD.match(code)
            if not m:
                fail(where, f"unsupported field declaration '{code}' (one-dimensional arrays only)")
            current.fields.append((m.group(1).split(".")[-1], m.group(2), m.group(3), comment, where))
    if current is not None:
        fail(f"{path}:{len(lines)}", f"struct {current.name} is not closed")
    return structs


def schema_of(s, structs):
    props = {}
    for ftype, fname, dim, comment, where in s.fields:
        if ftype in PRIMITIVES:
            item = dict(PRIMITIVES[ftype][1])
        elif ftype in structs:
            item = schema_of(structs[ftype], structs)
        else:
            fail(where, f"unknown type '{ftype}'")
        if dim is None:
            prop = item
        elif dim.isdigit():
            prop = {"type": "array", "items": item, "minItems": int(dim), "maxItems": int(dim)}
        else:
            prop = {"type": "array", "items": item}
        if comment:
            prop = dict(prop, description=comment)
        props[fname] = prop
    out = {"title": f"sextant.{s.name}", "type": "object"}
    if s.doc:
        out["description"] = s.doc
    out.update(properties=props, required=[f[1] for f in s.fields])
    return out


def to_json_body(s, structs):
    out = []
    for ftype, fname, dim, _, _ in s.fields:
        value = {"boolean": "Json(v != 0)"}.get(ftype, "json_value(v)") if ftype in PRIMITIVES else "to_json(v)"
        if dim is None:
            out.append(f'  {{ const auto& v = m.{fname}; j["{fname}"] = {value}; }}')
        else:
            size = dim if dim.isdigit() else f"m.{dim}"
            out.append(f'  {{ Json a = Json::array(); for (int i = 0; i < {size}; ++i) {{ const auto& v = m.{fname}[i]; '
                       f'a.push_back({value}); }} j["{fname}"] = std::move(a); }}')
    return "\n".join(out)


def reader(ftype, target, node, where):
    if ftype == "boolean":  # lcm-gen's C++ holds a boolean in an int8_t
        return f"read_boolean({node}, {target}, {where});"
    if ftype in PRIMITIVES:
        return f"read_value({node}, {target}, {where});"
    return f"from_json({node}, {target}, {where});"


def from_json_body(s, structs):
    out = []
    for ftype, fname, dim, _, where in s.fields:
        if ftype not in PRIMITIVES and ftype not in structs:
            fail(where, f"unknown type '{ftype}'")
        field = f'const Where w_{fname}{{&at, "{fname}"}}; const Json& f_{fname} = member(j, w_{fname});'
        if dim is None:
            out.append(f"  {{ {field} {reader(ftype, 'm.' + fname, 'f_' + fname, 'w_' + fname)} }}")
        else:
            size = dim if dim.isdigit() else f"m.{dim}"
            resize = "" if dim.isdigit() else f" m.{fname}.resize(static_cast<size_t>(m.{dim}));"
            elem = reader(ftype, f"m.{fname}[i]", f"f_{fname}[static_cast<size_t>(i)]", "we")
            out.append(f"  {{ {field} require_array(f_{fname}, {size}, w_{fname});{resize}\n"
                       f"    for (int i = 0; i < {size}; ++i) {{ const Where we{{&w_{fname}, nullptr, i}}; {elem} }} }}")
    return "\n".join(out)


def main():
    out_path, files = sys.argv[1], sys.argv[2:]
    structs = {}
    for path in files:
        for s in parse(path):
            structs[s.name] = s
    names = sorted(structs)
    src = ['// Generated by viewer/lcm_json_gen.py from lcmtypes/sextant/*.lcm; do not edit.',
           '#include "viewer/lcm_json.hpp"', '#include "viewer/lcm_json_support.hpp"', '']
    src += [f"#include <sextant/{n}.hpp>" for n in names]
    src += ["", "namespace sextant::viewer {", "namespace {", ""]
    for n in names:  # declarations first: nested structs may be defined in any order
        src.append(f"Json to_json(const sextant::{n}& m);")
        src.append(f"void from_json(const Json& j, sextant::{n}& m, const Where& at);")
    src.append("")
    for n in names:
        s = structs[n]
        src += [f"Json to_json(const sextant::{n}& m) {{", "  Json j = Json::object();", to_json_body(s, structs),
                "  return j;", "}", "",
                f"void from_json(const Json& j, sextant::{n}& m, const Where& at) {{", "  require_object(j, at);",
                from_json_body(s, structs), "}", ""]
    src += ["}  // namespace", "", "const std::vector<LcmJsonType>& lcm_json_types() {",
            "  static const std::vector<LcmJsonType> types = {"]
    for n in names:
        schema = json.dumps(schema_of(structs[n], structs), separators=(",", ":"))
        src.append(f'    make_lcm_json_type<sextant::{n}>("sextant.{n}", R"schema({schema})schema",')
        src.append(f"        [](const sextant::{n}& m) {{ return to_json(m); }},")
        src.append(f"        [](const Json& j, sextant::{n}& m, const Where& at) {{ from_json(j, m, at); }}),")
    src += ["  };", "  return types;", "}", "", "}  // namespace sextant::viewer", ""]
    text = "\n".join(src)
    try:
        with open(out_path) as f:
            if f.read() == text:
                return  # unchanged: keep the timestamp, nothing recompiles
    except OSError:
        pass
    with open(out_path, "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()

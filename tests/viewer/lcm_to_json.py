"""Decodes an LCM log into JSON lines with LCM's own Python decoders (lcm-gen's classes for sextant's types), so the
reference checks compare sextant's MCAP files with the log through code that shares nothing with sextant's C++.

Usage: lcm_to_json.py LOG.lcm OUT.jsonl
One line per event, in file order: {"channel", "timestamp" (us), "schema": "sextant.<type>", "message": {...}}, or
for bytes that no sextant type decodes {"channel", "timestamp", "raw": "<hex>"}.  A non-finite double is written as
the string "NaN", "Infinity" or "-Infinity" (the JSON form sextant documents in viewer/lcm_json.hpp).
"""
import importlib
import json
import math
import os
import pkgutil
import sys

from lcmlog import read_log  # tests/e2e/lcmlog.py

import sextant


def types_by_fingerprint():
    out = {}
    for m in pkgutil.iter_modules(sextant.__path__):
        cls = getattr(importlib.import_module(f"sextant.{m.name}"), m.name)
        out[cls._get_packed_fingerprint()] = cls
    return out


def plain(v):
    if isinstance(v, bool):
        return v
    if isinstance(v, float):
        if math.isnan(v):
            return "NaN"
        if math.isinf(v):
            return "Infinity" if v > 0 else "-Infinity"
        return v
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    if hasattr(v, "__slots__"):
        return {k: plain(getattr(v, k)) for k in v.__slots__}
    return v


def main():
    log, out_path = sys.argv[1], sys.argv[2]
    types = types_by_fingerprint()
    with open(out_path, "w") as out:
        for ts, channel, data in read_log(log):
            line = {"channel": channel, "timestamp": ts}
            cls = types.get(bytes(data[:8]))
            try:
                if cls is None:
                    raise ValueError("not a sextant type")
                line["schema"] = f"sextant.{cls.__name__}"
                line["message"] = plain(cls.decode(bytes(data)))
            except Exception:
                line.pop("schema", None)
                line["raw"] = bytes(data).hex()
            out.write(json.dumps(line, allow_nan=False) + "\n")


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(__file__))
    main()

#!/usr/bin/env python3
"""Fails when a doctest case name holds a ';': CMake splits a test name at ';', so ctest would register a name that
selects no case and report the test passed without running it.  Usage: check_test_names.py TEST_BINARY..."""
import subprocess
import sys

bad = []
for binary in sys.argv[1:]:
    names = subprocess.run([binary, "--list-test-cases"], capture_output=True, text=True, check=True).stdout
    bad += [f"{binary}: {n}" for n in names.splitlines() if ";" in n]
for b in bad:
    print(f"a test name with ';' (ctest would not run it): {b}")
sys.exit(1 if bad else 0)

#!/usr/bin/env python3
"""Lists C++ and Python functions longer than a limit (default 80 lines).

C++: a function is a brace block opened at namespace, class or file scope after a parenthesised parameter list
(constructors, operators and member functions included); its length counts the lines from its opening brace to its
closing brace, both included.  Lambdas and local classes count toward the function that holds them.  Comments,
string and character literals are blanked before the braces are matched.
Python: a `def` block, from its `def` line to its last non-blank line.

Usage: scripts/long_functions.py [--limit N] PATH...      (files or folders; prints `LINES path:line name`,
       longest first; exits 1 when any function is over the limit)
"""
import argparse
import os
import re
import sys

CPP_EXT = (".cpp", ".hpp", ".h", ".cc")


def blank_comments_and_strings(text):
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if m:
                end = text.find(")" + m.group(1) + '"', i)
                end = n if end < 0 else end + len(m.group(1)) + 2
                out.append(re.sub(r"[^\n]", " ", text[i:end]))
                i = end
            else:
                out.append(c)
                i += 1
        elif c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum():  # digit separator 1'000
                out.append(c)
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (j - i - 1) + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


SCOPE_WORDS = re.compile(r"\b(namespace|class|struct|union|enum)\b")


def cpp_functions(path):
    text = blank_comments_and_strings(open(path, encoding="utf-8", errors="replace").read())
    stack = []  # (kind, start offset, header)
    last_stmt_end = 0
    found = []
    for i, c in enumerate(text):
        if c == "{":
            header = text[last_stmt_end:i]
            in_function = any(k == "function" for k, _, _ in stack)
            kind = "block"
            if not in_function:
                h = header.strip()
                if SCOPE_WORDS.search(h) and not re.search(r"\)\s*(const|noexcept|override|final|\s)*$", h):
                    kind = "scope"
                elif "(" in h and not h.endswith("=") and not re.search(r"=\s*$", h):
                    kind = "function"
                elif h.startswith("extern"):
                    kind = "scope"
                else:
                    kind = "block"
            stack.append((kind, i, header))
            last_stmt_end = i + 1
        elif c == "}":
            if stack:
                kind, start, header = stack.pop()
                if kind == "function":
                    first = text.count("\n", 0, start) + 1
                    last = text.count("\n", 0, i) + 1
                    name = re.sub(r"\s+", " ", header.strip())
                    m = re.search(r"([~\w:<>=!+\-*/\[\]&|^%]+)\s*\(", name)
                    found.append((last - first + 1, first, m.group(1) if m else name[:60]))
            last_stmt_end = i + 1
        elif c == ";" and not any(k == "function" for k, _, _ in stack):
            last_stmt_end = i + 1
        elif c == ":" and not any(k == "function" for k, _, _ in stack):
            # access specifiers (public:) end a header; `::` and constructor initializer lists do not
            if text[i - 1 : i + 1] != "::" and text[i : i + 2] != "::" and re.search(r"\b(public|private|protected)\s*$", text[last_stmt_end:i]):
                last_stmt_end = i + 1
    return found


def python_functions(path):
    lines = open(path, encoding="utf-8", errors="replace").read().split("\n")
    found = []
    for i, line in enumerate(lines):
        m = re.match(r"(\s*)(async\s+)?def\s+(\w+)", line)
        if not m:
            continue
        indent = len(m.group(1))
        last = i
        for j in range(i + 1, len(lines)):
            s = lines[j]
            if not s.strip():
                continue
            if len(s) - len(s.lstrip()) <= indent:
                break
            last = j
        found.append((last - i + 1, i + 1, m.group(3)))
    return found


def files(paths):
    for p in paths:
        if os.path.isfile(p):
            yield p
        for root, dirs, names in os.walk(p):
            dirs[:] = sorted(d for d in dirs if d not in ("build", "node_modules", ".git", "__pycache__"))
            for name in sorted(names):
                if name.endswith(CPP_EXT + (".py",)):
                    yield os.path.join(root, name)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--limit", type=int, default=80)
    ap.add_argument("paths", nargs="+")
    a = ap.parse_args()
    rows = []
    for f in files(a.paths):
        fns = python_functions(f) if f.endswith(".py") else cpp_functions(f)
        rows += [(n, f, line, name) for n, line, name in fns if n > a.limit]
    for n, f, line, name in sorted(rows, key=lambda r: -r[0]):
        print(f"{n:5d} {f}:{line} {name}")
    return 1 if rows else 0


if __name__ == "__main__":
    sys.exit(main())

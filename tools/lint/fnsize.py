#!/usr/bin/env python3
"""Function size check for C sources (make lint-fnsize).

    tools/lint/fnsize.py [--max-lines N] [--max-depth N] [--max-file-lines N]
                         [--list] FILE...

Fails (exit 1) naming every function whose body is longer than --max-lines
(default 80) or nested deeper than --max-depth (default 4), and every file
longer than --max-file-lines (default 800); prints nothing and exits 0 when
all are within. --list also prints every function: body
lines, depth, file:line, name.

Body lines: the lines between the line of the opening brace and the line
of the closing brace. Depth: how deep braces nest inside the body, every
pair counted (a block of an if or a loop, a switch and each braced case
body, an initialiser), so `if (a) { while (b) { ... } }` is 2. Comments,
string and character literals and preprocessor lines are ignored; a
function is a top-level brace that follows a parameter list, with or
without GNU attributes. Braces split across #if branches are not
understood (the firmware has none).
"""
import argparse
import re
import sys

ATTRIBUTE_WORDS = {"__attribute__", "__declspec", "__asm__", "__asm", "asm"}


def blank(text):
    """The text with comments, literals and preprocessor lines replaced by
    spaces; newlines are kept, so offsets keep their line numbers."""
    out = []
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c in " \t":
            out.append(c)
            i += 1
            continue
        if line_start and c == "#":
            # A directive, with its backslash continuations.
            while i < n and text[i] != "\n":
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append(" \n")
                    i += 2
                    continue
                out.append(" ")
                i += 1
            continue
        line_start = False
        if c == "\n":
            out.append(c)
            line_start = True
            i += 1
        elif text.startswith("//", i):
            while i < n and text[i] != "\n":
                out.append(" ")
                i += 1
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            out.append(re.sub(r"[^\n]", " ", text[i:end]))
            i = end
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(" " * (j - i))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def open_paren(s, close):
    """Index of the "(" that the ")" at s[close] closes, or -1."""
    depth = 0
    for j in range(close, -1, -1):
        depth += s[j] == ")"
        depth -= s[j] == "("
        if depth == 0:
            return j
    return -1


def function_name(head):
    """The name a definition's head declares, or None when the head is not
    a function's (a struct, an initialiser, ...)."""
    head = head.strip()
    depth = 0
    for ch in head:
        depth += ch == "("
        depth -= ch == ")"
        if ch == "=" and depth == 0:
            return None
    while head.endswith(")"):
        j = open_paren(head, len(head) - 1)
        if j < 0:
            return None
        prefix = head[:j].rstrip()
        if prefix.endswith(")"):
            # A parenthesised declarator: int (*f(void))(int) { ... }
            k = open_paren(prefix, len(prefix) - 1)
            return function_name(prefix[k + 1 : -1]) if k >= 0 else None
        m = re.search(r"([A-Za-z_]\w*)\s*$", prefix)
        if not m:
            return None
        if m.group(1) not in ATTRIBUTE_WORDS:
            return m.group(1)
        head = prefix[: m.start()].rstrip()  # an attribute after the parameters
    return None


def functions(path):
    """(name, line of the opening brace, body lines, depth) of every
    function defined in the file at path."""
    with open(path, encoding="utf-8", errors="replace") as f:
        text = blank(f.read())
    found = []
    depth = 0
    head_start = 0
    current = None  # [name, offset of "{", deepest]
    for i, ch in enumerate(text):
        if ch == "{":
            if depth == 0:
                name = function_name(text[head_start:i])
                current = [name, i, 0] if name else None
            depth += 1
            if current:
                current[2] = max(current[2], depth - 1)
        elif ch == "}":
            depth -= 1
            if depth < 0:
                raise ValueError("%s:%d: unbalanced '}'" % (path, text.count("\n", 0, i) + 1))
            if depth == 0:
                if current:
                    first = text.count("\n", 0, current[1]) + 1
                    last = text.count("\n", 0, i) + 1
                    found.append((current[0], first, max(last - first - 1, 0), current[2]))
                current = None
                head_start = i + 1
        elif ch == ";" and depth == 0:
            head_start = i + 1
    if depth != 0:
        raise ValueError("%s: unbalanced '{' at the end" % path)
    return found


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--max-lines", type=int, default=80)
    ap.add_argument("--max-depth", type=int, default=4)
    ap.add_argument("--max-file-lines", type=int, default=800)
    ap.add_argument("--list", action="store_true", help="print every function's size")
    ap.add_argument("files", nargs="+")
    args = ap.parse_args(argv)
    over = []
    for path in args.files:
        try:
            fns = functions(path)
        except (OSError, ValueError) as e:
            print("fnsize: %s" % e, file=sys.stderr)
            return 2
        with open(path, encoding="utf-8") as f:
            file_lines = sum(1 for _ in f)
        if file_lines > args.max_file_lines:
            over.append("%s: %d lines (at most %d)" % (path, file_lines, args.max_file_lines))
        for name, line, lines, depth in fns:
            if args.list:
                print("%5d %2d %s:%d %s" % (lines, depth, path, line, name))
            why = []
            if lines > args.max_lines:
                why.append("%d body lines (at most %d)" % (lines, args.max_lines))
            if depth > args.max_depth:
                why.append("nesting depth %d (at most %d)" % (depth, args.max_depth))
            if why:
                over.append("%s:%d: %s: %s" % (path, line, name, ", ".join(why)))
    if over:
        for o in over:
            print(o, file=sys.stderr)
        print(
            "fnsize: %d function(s) or file(s) too long or too deeply nested: split them"
            % len(over),
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

#!/usr/bin/env python3
"""The include rules of the source tree (docs/architecture.md).

    tools/lint/includes.py [ROOT]     check every tracked C/C++ file under ROOT
    tools/lint/includes.py --self-test

Each quoted #include is resolved against the including file's folder, then
against the top (the build's -I.). Rules:

  firmware/     nothing outside firmware/ but hal/hal.h
  hal/*.h       the contract: nothing of ours at all
  hal/posix/    itself, the contract and firmware/config.h only
  proto/        (the unit's side) no platform, no hal/posix/, no host_sim/
  proto/client/ may use hal/posix/ (the only part of proto/ that does)
  hal/<platform>/ never another platform, never host_sim/
  host_sim/     no platform
  any two folders never include each other

Prints one line per violation and exits 1; silent and 0 when clean.
"""
import os
import re
import subprocess
import sys
import tempfile

PLATFORMS = ("hal/linux", "hal/cortexm")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def folder(path):
    return os.path.dirname(path) or "."


def under(path, top):
    return path == top or path.startswith(top + "/")


def platform_of(path):
    for p in PLATFORMS:
        if under(path, p):
            return p
    return None


def resolve(root, src, name):
    """The included file as a path from root, or None (a system header)."""
    for base in (folder(src), "."):
        cand = os.path.normpath(os.path.join(base, name))
        if os.path.isfile(os.path.join(root, cand)):
            return cand
    return None


def rule(src, dst):
    """Why src may not include dst, or None."""
    sf, df = folder(src), folder(dst)
    if under(src, "firmware"):
        if not (under(dst, "firmware") or dst == "hal/hal.h"):
            return "firmware/ includes only itself and hal/hal.h"
    elif sf == "hal":
        if df != "hal":
            return "the hal/ contract includes nothing of ours"
    elif under(src, "hal/posix"):
        if not (under(dst, "hal/posix") or df == "hal" or dst == "firmware/config.h"):
            return "hal/posix/ uses only the contract and firmware/config.h"
    if under(src, "proto") and not under(src, "proto/client"):
        if platform_of(dst) or under(dst, "hal/posix") or under(dst, "host_sim"):
            return "proto/ (the unit's side) includes no platform, hal/posix/ or host_sim/"
    if under(src, "proto/client") and (platform_of(dst) or under(dst, "host_sim")):
        return "the client library includes no platform or host_sim/"
    sp, dp = platform_of(src), platform_of(dst)
    if sp and dp and sp != dp:
        return "a platform never includes another platform"
    if sp and under(dst, "host_sim"):
        return "a platform never includes host_sim/"
    if under(src, "host_sim") and dp:
        return "host_sim/ includes no platform"
    return None


def tracked(root):
    out = subprocess.run(["git", "-C", root, "ls-files", "*.c", "*.h", "*.cc", "*.def"],
                         capture_output=True, text=True, check=True).stdout
    return [f for f in out.split("\n") if f]


def check(root, files):
    bad = []
    edges = {}
    for src in files:
        with open(os.path.join(root, src), encoding="utf-8", errors="replace") as f:
            text = f.read()
        for name in INCLUDE.findall(text):
            dst = resolve(root, src, name)
            if dst is None:
                continue
            why = rule(src, dst)
            if why:
                bad.append("%s: includes %s: %s" % (src, dst, why))
            sf, df = folder(src), folder(dst)
            if sf != df:
                edges.setdefault((sf, df), (src, dst))
    for (a, b), (src, dst) in sorted(edges.items()):
        if a < b and (b, a) in edges:
            back = edges[(b, a)]
            bad.append("%s/ and %s/ include each other (%s -> %s, %s -> %s)" %
                       (a, b, src, dst, back[0], back[1]))
    return bad


def self_test():
    """Every rule catches its violation, and a clean tree passes."""
    cases = {
        "firmware/a.c": '#include "../proto/x.h"',
        "hal/hal.h": '#include "posix/y.h"',
        "hal/posix/y.h": '#include "../../proto/x.h"',
        "proto/x.h": '#include "../hal/posix/y.h"',
        "proto/client/c.c": '#include "../../hal/linux/l.h"',
        "hal/linux/l.h": '#include "../cortexm/m.h"',
        "hal/cortexm/m.h": '#include "../../host_sim/s.h"',
        "host_sim/s.h": '#include "../hal/linux/l.h"',
        "tools/t.h": '#include "../tests/u.h"',
        "tests/u.h": '#include "../tools/t.h"',
    }
    expect = 10  # one per rule above, the last two as one mutual pair
    with tempfile.TemporaryDirectory() as d:
        for path, text in cases.items():
            os.makedirs(os.path.join(d, folder(path)), exist_ok=True)
            with open(os.path.join(d, path), "w") as f:
                f.write(text + "\n")
        found = check(d, list(cases))
        if len(found) != expect:
            print("includes self-test: %d violations found, %d expected:" % (len(found), expect))
            print("\n".join(found))
            return 1
        clean = {"firmware/a.c": '#include "../hal/hal.h"', "hal/hal.h": "",
                 "hal/posix/y.h": '#include "../link.h"\n#include "../../firmware/config.h"',
                 "hal/link.h": "", "firmware/config.h": "",
                 "proto/client/c.c": '#include "../../hal/posix/y.h"'}
        for path, text in clean.items():
            with open(os.path.join(d, path), "w") as f:
                f.write(text + "\n")
        found = check(d, list(clean))
        if found:
            print("includes self-test: a clean tree reported:\n" + "\n".join(found))
            return 1
    return 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    root = argv[1] if len(argv) > 1 else "."
    bad = check(root, tracked(root))
    for b in bad:
        print(b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

#!/usr/bin/env python3
"""Layering of object files: no cycle of symbol use among a set of objects.

    objdeps.py NAME OBJ...     fail (exit 1) naming every cycle, e.g. two
                               objects that use each other's symbols
    objdeps.py --self-test     prove that a pair and a longer cycle are
                               caught and a layered set passes

An object uses another when it leaves undefined a global symbol the other
defines (nm). A cycle means two files of a layer call each other, or a
lower layer calls back up: the engine's files are layered (firmware/
motion_priv.h) and this holds them to it.
"""
import os
import subprocess
import sys
import tempfile

NM = os.environ.get("NM", "nm")


def symbols(obj):
    out = subprocess.run([NM, obj], check=True, capture_output=True, text=True).stdout
    defined, undefined = set(), set()
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[1] in "TDBRCVW":
            defined.add(parts[2])
        elif len(parts) == 2 and parts[0] in ("U", "w"):
            undefined.add(parts[1])
    return defined, undefined


def graph(objs):
    syms = {o: symbols(o) for o in objs}
    edges = {}
    for a in objs:
        for b in objs:
            if a != b:
                used = syms[a][1] & syms[b][0]
                if used:
                    edges.setdefault(a, {})[b] = sorted(used)
    return edges


def cycles(objs, edges):
    """Strongly connected components of more than one object (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, {}):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in objs:
        if v not in index:
            visit(v)
    return found


def check(name, objs):
    edges = graph(objs)
    bad = cycles(objs, edges)
    for comp in bad:
        print(f"objdeps: {name}: a cycle among {', '.join(os.path.basename(o) for o in comp)}:")
        for a in comp:
            for b, used in sorted(edges.get(a, {}).items()):
                if b in comp:
                    print(f"  {os.path.basename(a)} uses {os.path.basename(b)}: {', '.join(used)}")
    return 0 if not bad else 1


def self_test():
    cc = os.environ.get("CC", "cc")
    cases = {
        # name: ({file: source}, expected exit)
        "pair": ({"a.c": "void b(void);\nvoid a(void) { b(); }\n",
                  "b.c": "void a(void);\nvoid b(void) { a(); }\n"}, 1),
        "three": ({"a.c": "void b(void);\nvoid a(void) { b(); }\n",
                   "b.c": "void c(void);\nvoid b(void) { c(); }\n",
                   "c.c": "void a(void);\nvoid c(void) { a(); }\n"}, 1),
        "data": ({"a.c": "extern int y;\nint x = 1;\nint a(void) { return y; }\n",
                  "b.c": "extern int x;\nint y = 2;\nint b(void) { return x; }\n"}, 1),
        "layered": ({"a.c": "void b(void);\nvoid c(void);\nvoid a(void) { b(); c(); }\n",
                     "b.c": "void c(void);\nvoid b(void) { c(); }\n",
                     "c.c": "void c(void) {}\n"}, 0),
    }
    with tempfile.TemporaryDirectory() as tmp:
        for case, (files, want) in cases.items():
            objs = []
            for fname, text in files.items():
                src = os.path.join(tmp, f"{case}_{fname}")
                with open(src, "w") as f:
                    f.write(text)
                obj = src[:-2] + ".o"
                subprocess.run([cc, "-c", "-O1", src, "-o", obj], check=True)
                objs.append(obj)
            with open(os.devnull, "w") as null:
                saved = sys.stdout
                sys.stdout = null
                try:
                    got = check(case, objs)
                finally:
                    sys.stdout = saved
            if got != want:
                print(f"objdeps self-test: case {case}: exit {got}, want {want}")
                return 1
    return 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    if len(argv) < 3:
        print(__doc__)
        return 2
    return check(argv[1], argv[2:])


if __name__ == "__main__":
    sys.exit(main(sys.argv))

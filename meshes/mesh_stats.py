#!/usr/bin/env python3
"""Statistics and sanity checks for the ASCII MSH 4.1 triangle meshes in meshes/.

Pure standard library (runs with any python3).  For every file it reports
cells (triangles), vertices (nodes used by triangles), the number of boundary
edges carrying each physical tag, the maximum triangle diameter (= longest
edge), and it checks that
  * every boundary edge of the triangulation is a line element in exactly one
    physical group (tags 1, 2, 3), and no line element is interior;
  * every triangle is in physical surface 10;
  * (optionally, --interface 0.5) no triangle straddles the line y = 0.5.
Exit status is non-zero if a check fails.

Usage: mesh_stats.py [--markdown] [--interface Y] FILE.msh ...
"""
import math
import sys


def physical_tags(lines, i, count):
    """{entity tag: physical tags} of the `count` curve or surface lines of $Entities from line i."""
    out = {}
    for w in (lines[i + j].split() for j in range(count)):
        nphys = int(w[7])
        out[int(w[0])] = [int(t) for t in w[8:8 + nphys]]
    return out


def blocks(lines, i, lines_per_entry):
    """The entity blocks of the $Nodes or $Elements section whose header is line i: a list of
    (block header as integers, line of its first entry), and the line after the last block. A
    block of n entries spans lines_per_entry * n lines after its header."""
    nblocks = int(lines[i + 1].split()[0])
    i += 2
    out = []
    for _ in range(nblocks):
        head = list(map(int, lines[i].split()))
        out.append((head, i + 1))
        i += 1 + lines_per_entry * head[3]
    return out, i


def read_msh41(path):
    with open(path) as fh:
        lines = fh.read().split("\n")
    i = 0
    n = len(lines)
    curve_phys = {}   # curve entity tag -> list of physical tags
    surf_phys = {}
    nodes = {}
    lines_el = []     # (entity tag, n1, n2)
    tris = []         # (entity tag, n1, n2, n3)
    while i < n:
        s = lines[i].strip()
        if s == "$MeshFormat":
            ver, ftype = lines[i + 1].split()[:2]
            if not ver.startswith("4.1") or ftype != "0":
                raise ValueError(f"{path}: expected ASCII MSH 4.1, got {ver} type {ftype}")
            i += 2
        elif s == "$Entities":
            np_, nc, ns, nv = map(int, lines[i + 1].split())
            i += 2 + np_
            curve_phys = physical_tags(lines, i, nc)
            surf_phys = physical_tags(lines, i + nc, ns)
            i += nc + ns + nv
        elif s == "$Nodes":
            # a block: the node tags, then their coordinates
            node_blocks, i = blocks(lines, i, 2)
            for (_dim, _tag, _param, nb), j in node_blocks:
                for k in range(nb):
                    x, y, _z = map(float, lines[j + nb + k].split())
                    nodes[int(lines[j + k])] = (x, y)
        elif s == "$Elements":
            element_blocks, i = blocks(lines, i, 1)
            for (_dim, etag, etype, nb), j in element_blocks:
                for k in range(nb):
                    w = list(map(int, lines[j + k].split()))
                    if etype == 1:
                        lines_el.append((etag, w[1], w[2]))
                    elif etype == 2:
                        tris.append((etag, w[1], w[2], w[3]))
                    elif etype == 15:
                        pass
                    else:
                        raise ValueError(f"{path}: unexpected element type {etype}")
        else:
            i += 1
    return curve_phys, surf_phys, nodes, lines_el, tris


def stats(path, interface=None):
    curve_phys, surf_phys, nodes, lines_el, tris = read_msh41(path)
    errors = []
    edge_count = {}
    used = set()
    hmax = 0.0
    straddle = 0
    for (etag, a, b, c) in tris:
        if surf_phys.get(etag) != [10]:
            errors.append(f"triangle in surface entity {etag} with physical tags {surf_phys.get(etag)}")
        used.update((a, b, c))
        for (p, q) in ((a, b), (b, c), (c, a)):
            e = (min(p, q), max(p, q))
            edge_count[e] = edge_count.get(e, 0) + 1
            (x1, y1), (x2, y2) = nodes[p], nodes[q]
            hmax = max(hmax, math.hypot(x1 - x2, y1 - y2))
        if interface is not None:
            ys = [nodes[v][1] for v in (a, b, c)]
            if min(ys) < interface - 1e-12 and max(ys) > interface + 1e-12:
                straddle += 1
    boundary = {e for e, k in edge_count.items() if k == 1}
    tagged = {}
    per_tag = {}
    for (etag, a, b) in lines_el:
        e = (min(a, b), max(a, b))
        ph = curve_phys.get(etag, [])
        if len(ph) != 1:
            errors.append(f"line entity {etag} has physical tags {ph}")
            continue
        tagged[e] = tagged.get(e, 0) + 1
        per_tag[ph[0]] = per_tag.get(ph[0], 0) + 1
        if e not in boundary:
            errors.append(f"line element {e} is not a boundary edge")
    for e in boundary:
        if tagged.get(e, 0) != 1:
            errors.append(f"boundary edge {e} is in {tagged.get(e, 0)} physical groups")
    if straddle:
        errors.append(f"{straddle} triangles straddle y = {interface}")
    return {
        "file": path.split("/")[-1],
        "cells": len(tris),
        "vertices": len(used),
        "nodes": len(nodes),
        "g1": per_tag.get(1, 0),
        "g2": per_tag.get(2, 0),
        "g3": per_tag.get(3, 0),
        "hmax": hmax,
        "errors": errors,
    }


def main(argv):
    markdown = False
    interface = None
    files = []
    it = iter(argv)
    for a in it:
        if a == "--markdown":
            markdown = True
        elif a == "--interface":
            interface = float(next(it))
        else:
            files.append(a)
    bad = 0
    if markdown:
        print("| file | cells | vertices | edges on Γ1 | edges on Γ2 | edges on Γ3 | max triangle diameter |")
        print("|---|---:|---:|---:|---:|---:|---:|")
    else:
        print(f"{'file':<18}{'cells':>8}{'vertices':>10}{'E(G1)':>7}{'E(G2)':>7}{'E(G3)':>7}{'max diam':>12}")
    for f in files:
        itf = interface if (interface is not None and "test2" in f) else None
        s = stats(f, itf)
        if markdown:
            print(f"| {s['file']} | {s['cells']} | {s['vertices']} | {s['g1']} | {s['g2']} | {s['g3']} | {s['hmax']:.5f} |")
        else:
            print(f"{s['file']:<18}{s['cells']:>8}{s['vertices']:>10}{s['g1']:>7}{s['g2']:>7}{s['g3']:>7}{s['hmax']:>12.5f}")
        if s["nodes"] != s["vertices"]:
            s["errors"].append(f"{s['nodes'] - s['vertices']} nodes not used by any triangle")
        for e in s["errors"][:10]:
            print(f"ERROR {s['file']}: {e}", file=sys.stderr)
        bad += bool(s["errors"])
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

#!/usr/bin/env python3
# kdmesh — the tables of tools/bench/real_parts.sh: per-case CSV rows and docs/real_parts.md.
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Usage:
  real_parts_report.py add --results CSV --tool T --part P --div N --h H --rc RC --vrc VRC
                           --timeout S --dir CASEDIR --version V --cmd CMD
      reads CASEDIR/{time.txt,stderr.txt,verify.json,summary.json}; replaces the row of
      (T, P, N) in CSV, or appends it (the file is rewritten atomically)
  real_parts_report.py reclass --results CSV --work WORKDIR
      recomputes the error class of failed rows from WORKDIR/cases/TOOL/PART/DIV
  real_parts_report.py corpus --out CSV 'part|package|path|flag|facts.json' ...
  real_parts_report.py report --results CSV --corpus CSV --out MD
      (includes notes.md from the CSV's directory, hand-written, after the failure table)
"""
import argparse
import csv
import json
import os
import re
import statistics
import sys
import time

COLUMNS = ["tool", "part", "div", "h", "status", "exit_code", "error_class", "wall_s", "peak_kib",
           "tets", "verified", "reasons", "min_dihedral", "max_dihedral", "share_under_10",
           "share_under_5", "tets_under_5", "tets_over_165", "volume_rel_err", "bdist_over_h",
           "mean_edge_over_h", "away_edges", "away_edge_over_h", "tets_per_s", "verify_s",
           "version", "date"]
# The issue's size-fidelity target: mean edge / h within this range away from refinement.
FIDELITY = (0.9, 1.15)
TOOLS = ["kdmesh", "tetgen", "gmsh", "mesh3"]
TOOL_NAMES = {"kdmesh": "kdmesh", "tetgen": "TetGen -pq1.414a", "gmsh": "Gmsh HXT",
              "mesh3": "CGAL Mesh_3"}
KDMESH_EXIT = {1: "internal error", 2: "bad command line", 3: "unreadable input",
               4: "no valid result (input)", 5: "check failed", 6: "output not written",
               7: "memory limit"}


def _read_csv(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _write_csv(path, rows, columns):
    tmp = f"{path}.tmp-{os.getpid()}"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in columns})
    os.replace(tmp, path)


def _time_v(path):
    wall, peak = None, None
    if os.path.exists(path):
        for line in open(path, errors="replace"):
            line = line.strip()
            if line.startswith("Elapsed (wall clock) time"):
                t = line.rsplit(" ", 1)[-1].split(":")
                wall = sum(float(x) * 60 ** i for i, x in enumerate(reversed(t)))
            elif line.startswith("Maximum resident set size"):
                peak = int(line.rsplit(" ", 1)[-1])
    return wall, peak


def _error_class(tool, rc, stderr, stdout):
    """A short class of a failed run: the exit code's meaning and the message without numbers,
    paths and names."""
    # TetGen prints its error to stdout and then aborts (stderr: "terminate called ...")
    text = (stdout + "\n" + stderr if tool == "tetgen" else stderr + "\n" + stdout).strip()
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    if tool == "gmsh":
        errs = [ln for ln in lines if ln.startswith("Error")]
        msg = errs[0] if errs else (lines[-1] if lines else "")
    elif tool == "tetgen":
        errs = [ln for ln in lines if re.search(r"error|invalid|intersect|fail|abort|terminate",
                                                 ln, re.I)]
        msg = errs[0] if errs else (lines[-1] if lines else "")
    else:
        idx = [i for i, ln in enumerate(lines) if re.search(r"error|fail|invalid|not ", ln, re.I)]
        msg = lines[idx[0]] if idx else (lines[-1] if lines else "")
        if idx and msg.endswith(":") and idx[0] + 1 < len(lines):  # the detail on the next line
            msg += " " + lines[idx[0] + 1]
        msg = re.sub(r"^kdmesh: error: (job '[^']*': )?", "", msg)
        msg = re.sub(r",? e\.g\. .*", "", msg)  # the examples (coordinates) of a check failure
    msg = re.sub(r"(/[^\s:'\"]+)+", "PATH", msg)
    msg = re.sub(r"'[^']*'", "'…'", msg)
    msg = re.sub(r"[-+]?\d+(\.\d+)?([eE][-+]?\d+)?", "N", msg)
    msg = msg.replace("|", "/")[:110]
    sig = {134: " (SIGABRT)", 136: " (SIGFPE)", 137: " (SIGKILL)", 139: " (SIGSEGV)"}.get(rc, "")
    if sig and tool != "tetgen":
        msg = ""  # a crash: the last line is only where it was
    head = KDMESH_EXIT.get(rc, f"exit {rc}") if tool == "kdmesh" else f"exit {rc}{sig}"
    return f"{head}: {msg}" if msg else head


def cmd_add(a):
    d = a.dir
    wall, peak = _time_v(os.path.join(d, "time.txt"))
    rc = int(a.rc)

    def rd(name):
        p = os.path.join(d, name)
        return open(p, errors="replace").read() if os.path.exists(p) else ""
    row = {"tool": a.tool, "part": a.part, "div": a.div, "h": "%.6g" % float(a.h),
           "exit_code": rc, "wall_s": "" if wall is None else "%.2f" % wall,
           "peak_kib": "" if peak is None else peak, "version": a.version,
           "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    if rc in (124, 137) or (wall is not None and wall >= float(a.timeout) - 0.5 and rc != 0):
        row["status"] = "timeout"
        row["error_class"] = f"timeout ({a.timeout} s)"
    elif rc != 0:
        row["status"] = "error"
        row["error_class"] = _error_class(a.tool, rc, rd("stderr.txt"), rd("stdout.txt"))
    elif a.vrc == "-":
        row["status"] = "no-output"
        row["error_class"] = "exit 0 without a mesh"
    else:
        row["status"] = "ok"
    v = None
    if a.vrc not in ("-",):
        p = os.path.join(d, "verify.json")
        if os.path.exists(p) and os.path.getsize(p):
            v = json.load(open(p))
        elif int(a.vrc) in (124, 137):
            row["verified"] = "verify-timeout"
        else:
            row["verified"] = "verify-crash"
            row["reasons"] = rd("verify_stderr.txt").strip().splitlines()[-1:][0][:200] \
                if rd("verify_stderr.txt").strip() else ""
    if v is not None:
        row["verified"] = "pass" if v.get("pass") else "fail"
        row["reasons"] = "; ".join(v.get("reasons", []))[:300]
        fmt = {"min_dihedral": ("min_dihedral_deg", "%.3f"), "max_dihedral": ("max_dihedral_deg", "%.3f"),
               "share_under_10": ("share_min_dihedral_under_10", "%.6f"),
               "share_under_5": ("share_min_dihedral_under_5", "%.6f"),
               "tets_under_5": ("tets_min_dihedral_under_5", "%d"),
               "tets_over_165": ("tets_max_dihedral_over_165", "%d"),
               "volume_rel_err": ("volume_rel_err", "%.3e"),
               "bdist_over_h": ("boundary_max_dist_over_h", "%.4f"),
               "mean_edge_over_h": ("mean_edge_over_h", "%.4f"), "tets": ("tets", "%d"),
               "away_edges": ("away_edges", "%d"), "away_edge_over_h": ("away_edge_over_h", "%.4f"),
               "verify_s": ("verify_seconds", "%.2f")}
        for col, (key, f) in fmt.items():
            if v.get(key) is not None:
                row[col] = f % v[key]
        if v.get("tets") and wall:
            row["tets_per_s"] = "%.0f" % (v["tets"] / max(wall, 1e-3))
    rows = [r for r in _read_csv(a.results)
            if (r["tool"], r["part"], r["div"]) != (a.tool, a.part, str(a.div))]
    rows.append(row)
    order = {t: i for i, t in enumerate(TOOLS)}
    rows.sort(key=lambda r: (r["part"], int(r["div"]), order.get(r["tool"], 9)))
    _write_csv(a.results, rows, COLUMNS)
    ok = row["status"] == "ok" and row.get("verified") == "pass"
    print(f"real_parts: {a.tool:6s} {a.part:22s} /{a.div:<3} {row['status']:8s} "
          f"{row.get('verified', '-'):6s} tets={row.get('tets', '-'):>8} "
          f"min={row.get('min_dihedral', '-'):>7} wall={row['wall_s']:>7}s"
          + ("" if ok else f"  [{row.get('error_class') or row.get('reasons', '')}]"[:160]),
          flush=True)


def cmd_reclass(a):
    """Recomputes the error class of the failed rows from their case directories (after a
    change of _error_class), where those still exist."""
    rows = _read_csv(a.results)
    n = 0
    for r in rows:
        d = os.path.join(a.work, "cases", r["tool"], r["part"], r["div"])
        if r["status"] != "error" or not os.path.isdir(d):
            continue

        def rd(name):
            p = os.path.join(d, name)
            return open(p, errors="replace").read() if os.path.exists(p) else ""
        c = _error_class(r["tool"], int(r["exit_code"]), rd("stderr.txt"), rd("stdout.txt"))
        if c != r["error_class"]:
            r["error_class"] = c
            n += 1
    _write_csv(a.results, rows, COLUMNS)
    print(f"real_parts_report: {n} error classes updated")


CORPUS_COLUMNS = ["part", "package", "source", "flag", "facets", "bbox_diag", "volume",
                  "min_input_dihedral", "max_input_dihedral", "input_edges_under_12"]


def cmd_corpus(a):
    rows = []
    for spec in a.items:
        part, pkg, src, flag, facts = spec.split("|")
        f = json.load(open(facts))
        rows.append({"part": part, "package": pkg, "source": src, "flag": flag,
                     "facets": f["facets"], "bbox_diag": "%.6g" % f["bbox_diag"],
                     "volume": "%.6g" % f["volume"],
                     "min_input_dihedral": "%.2f" % f["min_dihedral_deg"]
                     if f.get("min_dihedral_deg") is not None else "",
                     "max_input_dihedral": "%.2f" % f["max_dihedral_deg"]
                     if f.get("max_dihedral_deg") is not None else "",
                     "input_edges_under_12": f.get("edges_under_12deg", "")})
    _write_csv(a.out, rows, CORPUS_COLUMNS)


def _f(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return None


def _med(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def _fmt(x, f="%.2f"):
    return "–" if x is None else f % x


def _meets_angles(r, corpus):
    """Max dihedral <= 165 deg, no tet under 5 deg, and min dihedral >= 12 deg unless the
    part's own sharpest edge is under 12 deg (then no mesh can have it there)."""
    sharp = _f(corpus.get(r["part"], {}).get("min_input_dihedral"))
    allows = sharp is None or sharp >= 12
    return (_f(r["max_dihedral"]) <= 165 and int(r.get("tets_under_5") or 0) == 0 and
            (_f(r["min_dihedral"]) >= 12 or not allows))


def _fidelity(good):
    """Median (range) of the away-from-refinement edge / h, and how many meshes are in range
    (of those with such edges)."""
    xs = [_f(r.get("away_edge_over_h")) for r in good if r.get("away_edge_over_h")]
    if not xs:
        return "–"
    inside = sum(FIDELITY[0] <= x <= FIDELITY[1] for x in xs)
    return f"{_med(xs):.3f} ({min(xs):.3f}–{max(xs):.3f}), {inside}/{len(xs)}"


def cmd_report(a):
    rows = _read_csv(a.results)
    corpus = {r["part"]: r for r in _read_csv(a.corpus)}
    tools = [t for t in TOOLS if any(r["tool"] == t for r in rows)]
    divs = sorted({int(r["div"]) for r in rows})
    out = []
    w = out.append
    w("# Real parts: kdmesh, TetGen, Gmsh and CGAL Mesh_3 on third-party CAD parts and scans")
    w("")
    w("Generated by `tools/bench/real_parts.sh` (issue 18, item 5) from "
      f"`{os.path.relpath(a.results, os.path.dirname(os.path.abspath(a.out)))}`; do not edit by "
      "hand. Every mesh is checked by `tools/bench/verify_tets.py`, which uses no kdmesh code. "
      "A case **succeeds** when the mesher exits 0 within its time limit and the verifier "
      "passes: every tet positive, conforming (no face in 3 tets, no fold), a closed oriented "
      "2-manifold boundary, |volume − input volume| ≤ 0.5 % of the input volume, every boundary "
      "vertex within 1e-6 × bbox diagonal of the input surface. h = bbox diagonal / N.")
    w("")
    w("Targets (issue 18): every valid part meshes at all three sizes and passes; min "
      "dihedral ≥ 12° wherever the input's own angles allow it; no tet under 5°; max dihedral "
      f"≤ 165°; size fidelity in [{FIDELITY[0]}, {FIDELITY[1]}]: the mean edge / h over the "
      "edges away from the automatic refinement (both ends at the size asked for, by the "
      "target size the mesher records per node; only kdmesh records one).")
    w("")
    w("Tools: kdmesh `mesh PART --size h`; TetGen `-pq1.414a<V>` with V = h³/(6√2) (a regular "
      "tet of edge h; TetGen keeps and only splits the input triangles, so its boundary "
      "distance is 0 and its edges near fine input facets are short); Gmsh 4.8: Merge, "
      "ClassifySurfaces{40°, 1, 1, π}, CreateGeometry, one volume, HXT (Mesh.Algorithm3D = 10), "
      "MeshSizeMin = MeshSizeMax = h, default optimiser, 2 threads; CGAL Mesh_3 "
      "(`tools/bench/mesh3_part.cpp`): Polyhedral_mesh_domain_with_features_3, detect_features "
      "(60°), edge_size = facet_size = cell_size = h, facet_angle 25°, facet_distance = h/10, "
      "cell_radius_edge_ratio 3, perturb + exude, sequential.")
    w("")
    versions = {}
    for r in rows:
        versions.setdefault(r["tool"], set()).add(r["version"])
    dates = sorted(r["date"] for r in rows if r.get("date"))
    if dates:
        w(f"Runs from {dates[0]} to {dates[-1]} on the project's 2-core machine (shared; wall "
          "times are indicative). Versions: " +
          "; ".join(f"{t}: {', '.join(sorted(versions[t]))}" for t in tools) + ".")
        w("")

    # ---- summary
    w("## Summary per tool")
    w("")
    head = ["tool", "success"] + [f"/{d}" for d in divs] + [
        "meets targets", "min dihedral median (worst)", "max dihedral median (worst)",
        "share < 10° median", "meshes with a tet < 5°", "volume error median (max)",
        "boundary dist / h median (max)", "mean edge / h median",
        f"edge / h away from refinement median (range), in [{FIDELITY[0]}, {FIDELITY[1]}]",
        "tets/s median"]
    w("| " + " | ".join(head) + " |")
    w("|" + "---|" * len(head))
    for t in tools:
        rs = [r for r in rows if r["tool"] == t]
        good = [r for r in rs if r["status"] == "ok" and r.get("verified") == "pass"]

        def rate(sub, ok):
            return f"{len(ok)}/{len(sub)} ({100 * len(ok) / len(sub):.0f} %)" if sub else "–"
        per = []
        for d in divs:
            sub = [r for r in rs if int(r["div"]) == d]
            per.append(rate(sub, [r for r in sub if r in good]))
        mins = [_f(r["min_dihedral"]) for r in good]
        maxs = [_f(r["max_dihedral"]) for r in good]
        targets = [r for r in good if _meets_angles(r, corpus)]
        under5 = [r for r in good if int(r["tets_under_5"] or 0) > 0]
        vol = [_f(r["volume_rel_err"]) for r in good]
        bd = [_f(r["bdist_over_h"]) for r in good]
        w("| " + " | ".join([
            TOOL_NAMES[t], rate(rs, good), *per, f"{len(targets)}/{len(rs)}",
            f"{_fmt(_med(mins))}° ({_fmt(min(mins) if mins else None)}°)",
            f"{_fmt(_med(maxs))}° ({_fmt(max(maxs) if maxs else None)}°)",
            _fmt(_med([100 * _f(r['share_under_10']) for r in good]), "%.2f %%"),
            f"{len(under5)}/{len(good)}",
            f"{_fmt(_med([100 * x for x in vol if x is not None]), '%.3f %%')} "
            f"({_fmt(max(100 * x for x in vol if x is not None) if vol else None, '%.3f %%')})",
            f"{_fmt(_med(bd), '%.4f')} ({_fmt(max(x for x in bd if x is not None) if bd else None, '%.4f')})",
            _fmt(_med([_f(r['mean_edge_over_h']) for r in good]), "%.3f"),
            _fidelity(good),
            _fmt(_med([_f(r['tets_per_s']) for r in good]), "%.0f")]) + " |")
    w("")
    w("Medians and worst values are over the successful cases. \"meets targets\": succeeded "
      "with max dihedral ≤ 165°, no tet under 5°, and min dihedral ≥ 12° where the part's "
      "sharpest input edge allows it (out of all cases of the tool).")
    w("")

    # ---- failures
    w("## Failures by class")
    w("")
    w("| tool | class | cases |")
    w("|---|---|---|")
    for t in tools:
        classes = {}
        for r in rows:
            if r["tool"] != t or (r["status"] == "ok" and r.get("verified") == "pass"):
                continue
            if r["status"] != "ok":
                c = r["error_class"] or r["status"]
            else:
                c = "verifier: " + re.sub(r"[-+]?\d+(\.\d+)?([eE][-+]?\d+)?", "N",
                                          (r.get("reasons") or r.get("verified") or "")
                                          .split(";")[0])[:90]
            classes.setdefault(c, []).append(f"{r['part']}/{r['div']}")
        for c, cases in sorted(classes.items(), key=lambda kv: -len(kv[1])):
            w(f"| {TOOL_NAMES[t]} | {c.replace('|', '/')} | {len(cases)}: {', '.join(cases)} |")
    w("")

    # ---- per part
    w("## Per part")
    w("")
    w("Each cell: the result at " + ", ".join(f"/{d}" for d in divs) + " (P pass, F mesh written "
      "but the verifier fails it, E mesher error, T timeout, · not run), then the smallest min "
      "dihedral over the passing sizes.")
    w("")
    w("| part | sharpest input edge | " + " | ".join(TOOL_NAMES[t] for t in tools) + " |")
    w("|" + "---|" * (2 + len(tools)))
    index = {(r["tool"], r["part"], int(r["div"])): r for r in rows}
    for part in sorted({r["part"] for r in rows}):
        cells = []
        for t in tools:
            code, mins = "", []
            for d in divs:
                r = index.get((t, part, d))
                if r is None:
                    code += "·"
                elif r["status"] == "ok" and r.get("verified") == "pass":
                    code += "P"
                    mins.append(_f(r["min_dihedral"]))
                elif r["status"] == "ok":
                    code += "F"
                elif r["status"] == "timeout":
                    code += "T"
                else:
                    code += "E"
            cells.append(code + (f" {min(mins):.1f}°" if mins else ""))
        sharp = corpus.get(part, {}).get("min_input_dihedral", "")
        w(f"| {part} | {sharp}° | " + " | ".join(cells) + " |")
    w("")

    # ---- hand-written notes beside the CSV (kept across re-runs)
    notes = os.path.join(os.path.dirname(os.path.abspath(a.results)), "notes.md")
    if os.path.exists(notes):
        w(open(notes).read().rstrip())
        w("")

    # ---- corpus
    w("## Corpus")
    w("")
    w("`bash models/real/fetch.sh` fetches these from Debian 12 packages (sources, checksums and "
      "the parts left out: the comments there). \"sharpest input edge\" is the smallest "
      "dihedral angle of the part's own surface, inside the solid: a part with an edge under "
      "12° cannot have every tet ≥ 12° at that edge.")
    w("")
    w("| part | package | facets | bbox diagonal | sharpest input edge | input edges < 12° | "
      "input allows 12° | benchmark |")
    w("|---|---|---|---|---|---|---|---|")
    for p, c in corpus.items():
        allows = "yes" if (_f(c["min_input_dihedral"]) or 0) >= 12 else "**no**"
        w(f"| {p} | {c['package']} | {c['facets']} | {c['bbox_diag']} | "
          f"{c['min_input_dihedral']}° | {c['input_edges_under_12']} | {allows} | {c['flag']} |")
    w("")

    # ---- cases
    w("## Every case")
    w("")
    w("| part | h | tool | result | tets | min dih | max dih | < 10° | tets < 5° | vol err | "
      "bdist/h | edge/h | edge/h away (edges) | wall s | peak MiB | tets/s |")
    w("|" + "---|" * 16)
    for r in rows:
        if r["status"] == "ok" and r.get("verified") == "pass":
            res = "pass"
        elif r["status"] == "ok":
            res = f"verify {r.get('verified', '')}: {r.get('reasons', '')[:70]}"
        else:
            res = f"{r['status']}: {r.get('error_class', '')[:70]}"
        peak = _f(r.get("peak_kib"))
        w("| " + " | ".join([
            r["part"], f"/{r['div']}", TOOL_NAMES.get(r["tool"], r["tool"]), res.replace("|", "/"),
            r.get("tets") or "–", r.get("min_dihedral") or "–", r.get("max_dihedral") or "–",
            _fmt(100 * _f(r["share_under_10"]), "%.2f %%") if r.get("share_under_10") else "–",
            r.get("tets_under_5") or "–",
            _fmt(100 * _f(r["volume_rel_err"]), "%.3f %%") if r.get("volume_rel_err") else "–",
            r.get("bdist_over_h") or "–", r.get("mean_edge_over_h") or "–",
            f"{r['away_edge_over_h']} ({r['away_edges']})" if r.get("away_edge_over_h") else "–",
            r.get("wall_s") or "–",
            _fmt(peak / 1024 if peak else None, "%.0f"), r.get("tets_per_s") or "–"]) + " |")
    w("")
    tmp = a.out + f".tmp-{os.getpid()}"
    with open(tmp, "w") as f:
        f.write("\n".join(out))
    os.replace(tmp, a.out)


def main(argv):
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="action", required=True)
    p = sub.add_parser("add")
    for k in ("results", "tool", "part", "div", "h", "rc", "vrc", "timeout", "dir", "version", "cmd"):
        p.add_argument("--" + k, required=True)
    p = sub.add_parser("reclass")
    p.add_argument("--results", required=True)
    p.add_argument("--work", required=True)
    p = sub.add_parser("corpus")
    p.add_argument("--out", required=True)
    p.add_argument("items", nargs="*")
    p = sub.add_parser("report")
    p.add_argument("--results", required=True)
    p.add_argument("--corpus", required=True)
    p.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    {"add": cmd_add, "corpus": cmd_corpus, "report": cmd_report, "reclass": cmd_reclass}[a.action](a)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

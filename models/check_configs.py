#!/usr/bin/env python3
# kdmesh — checks the shipped batch files against the pinned batch schema (pure Python + PyYAML).
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Usage: check_configs.py [BATCH.yaml...]   (default: every models/**/*.yaml)

Independent of kdmesh's own loader: checks every job (defaults merged under it) against the
batch schema of docs/models.md (allowed keys, required keys, types, > 0 sizes, name pattern
and uniqueness, known orders and checks, zone shapes), that each input file exists next to
the YAML file, that each zone's coordinates meet the input's bounding box (a zone outside
the solid is a mistake), that outputs are bare file names, and that models/all.yaml's jobs
equal the ones of the per-model files. Exit 0 when all pass, 1 otherwise.
"""
import glob
import math
import os
import re
import sys

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_stl import read_surface  # noqa: E402

# The keys the shipped files use (tools/app/job_config.cpp has them all).
JOB_KEYS = {"name", "input", "bodies", "scale", "size", "min_size", "gradation", "sharp_angle", "zones",
            "order", "seed", "check", "output", "groups"}
ORDERS = {"kd-bfs", "kd-bfs-alt", "kd-bfs-hilbert", "kd-local", "hilbert", "brio", "random", "input"}
CHECKS = {"tetgen", "delaunay"}
OUTPUTS = {"vtu", "summary", "nodes", "msh", "inp", "mesh", "boundary_vtu", "xdmf", "exodus"}
ZONE_KEYS = {
    "sharp_edges": {"angle"}, "polyline": {"points"}, "segment": {"from", "to"},
    "plane": {"origin", "normal"}, "point": {"at"}, "box": {"min", "max"},
    "ball": {"center", "radius"},
}


def is_num(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def is_vec(x):
    return isinstance(x, list) and len(x) == 3 and all(is_num(c) for c in x)


def bbox_of(path, scale):
    pts = [p for t in read_surface(path) for p in t]
    return ([scale * min(p[a] for p in pts) for a in range(3)],
            [scale * max(p[a] for p in pts) for a in range(3)])


def check_job(where, job, base, errors):
    def err(msg):
        errors.append(f"{where}: job {job.get('name', '?')}: {msg}")
    for k in job:
        if k not in JOB_KEYS:
            err(f"unknown key {k!r}")
    for k in ("name", "size"):
        if k not in job:
            err(f"missing required key {k!r}")
    if ("input" in job) == ("bodies" in job):
        err("exactly one of 'input' and 'bodies' is required")
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", str(job.get("name", ""))):
        err("name must match [A-Za-z0-9_.-]+")
    for k in ("scale", "size", "min_size", "gradation"):
        if k in job and not (is_num(job[k]) and job[k] > 0):
            err(f"{k} must be a number > 0")
    if "sharp_angle" in job and not (is_num(job["sharp_angle"]) and 0 <= job["sharp_angle"] <= 180):
        err("sharp_angle must be in [0, 180] degrees")
    if "order" in job and job["order"] not in ORDERS:
        err(f"order {job['order']!r} unknown")
    if "seed" in job and not (isinstance(job["seed"], int) and job["seed"] >= 0):
        err("seed must be an unsigned integer")
    if "check" in job and not (isinstance(job["check"], list)
                               and all(c in CHECKS for c in job["check"])):
        err(f"check must be a list of {sorted(CHECKS)}")
    out = job.get("output", {}) or {}
    for k, v in out.items():
        if k not in OUTPUTS:
            err(f"output key {k!r} unknown")
        elif not isinstance(v, str) or "/" in v:
            err(f"output {k} must be a bare file name")
    box = None
    bodies = job.get("bodies")
    if bodies is not None and not (isinstance(bodies, list) and bodies and all(
            isinstance(b, dict) and set(b) == {"name", "input"} for b in bodies)):
        err("bodies must be a non-empty list of {name, input}")
        bodies = []
    names = [str(b["name"]) for b in bodies or []]
    if len(set(names)) != len(names) or not all(re.fullmatch(r"[A-Za-z0-9_-]+", n) for n in names):
        err("body names must be distinct and match [A-Za-z0-9_-]+")
    for rel in [b["input"] for b in bodies] if bodies is not None else [job.get("input", "")]:
        inp = os.path.join(base, str(rel))
        if not os.path.isfile(inp):
            err(f"input {inp} does not exist")
        elif not inp.lower().endswith((".stl", ".ply")):
            err("input must be STL or PLY")
        else:  # the zones must meet the union of the inputs' boxes
            lo, hi = bbox_of(inp, job.get("scale", 1.0))
            box = (lo, hi) if box is None else ([min(a, b) for a, b in zip(box[0], lo)],
                                                [max(a, b) for a, b in zip(box[1], hi)])
    for i, z in enumerate(job.get("zones", []) or []):
        zw = f"zone {i} ({z.get('name', z.get('type'))})"
        t = z.get("type")
        if t not in ZONE_KEYS:
            err(f"{zw}: type {t!r} unknown")
            continue
        for k in z:
            if k not in ZONE_KEYS[t] | {"type", "size", "name"}:
                err(f"{zw}: unknown key {k!r}")
        if not (is_num(z.get("size")) and z["size"] > 0):
            err(f"{zw}: size must be > 0")
        if is_num(z.get("size")) and is_num(job.get("size")) and z["size"] > job["size"]:
            err(f"{zw}: size {z['size']} above the job's size {job['size']} has no effect")
        pts = []
        if t == "polyline":
            pts = z.get("points", [])
            if not (isinstance(pts, list) and len(pts) >= 2 and all(is_vec(p) for p in pts)):
                err(f"{zw}: points must be >= 2 [x,y,z]")
                pts = []
        elif t == "segment":
            pts = [z.get("from"), z.get("to")]
        elif t == "plane":
            pts = [z.get("origin")]
            n = z.get("normal")
            if not is_vec(n) or all(c == 0 for c in n):
                err(f"{zw}: normal must be a non-zero [x,y,z]")
        elif t == "point":
            pts = [z.get("at")]
        elif t == "box":
            pts = [z.get("min"), z.get("max")]
        elif t == "ball":
            pts = [z.get("center")]
            if not (is_num(z.get("radius")) and z["radius"] > 0):
                err(f"{zw}: radius must be > 0")
        if any(not is_vec(p) for p in pts):
            err(f"{zw}: coordinates must be [x,y,z]")
            continue
        if box and t != "sharp_edges" and t != "plane":
            lo, hi = box
            for p in pts:
                if any(p[a] < lo[a] or p[a] > hi[a] for a in range(3)):
                    err(f"{zw}: point {p} outside the input's bounding box {lo} - {hi}")
        if box and t == "plane" and is_vec(z.get("normal")):
            lo, hi = box
            n, o = z["normal"], z["origin"]
            vals = [sum(n[a] * ((hi if (c >> a) & 1 else lo)[a] - o[a]) for a in range(3))
                    for c in range(8)]
            if min(vals) > 0 or max(vals) < 0:
                err(f"{zw}: plane misses the input's bounding box")


def load_jobs(path, errors):
    with open(path) as f:
        doc = yaml.safe_load(f)
    if not isinstance(doc, dict) or set(doc) - {"defaults", "jobs"}:
        errors.append(f"{path}: top level must have only 'defaults' and 'jobs'")
        return {}
    defaults = doc.get("defaults") or {}
    for k in defaults:
        if k not in JOB_KEYS:
            errors.append(f"{path}: defaults: unknown key {k!r}")
    jobs = doc.get("jobs")
    if not isinstance(jobs, list) or not jobs:
        errors.append(f"{path}: 'jobs' must be a non-empty list")
        return {}
    out = {}
    for j in jobs:
        m = dict(defaults)
        m.update(j)
        if m.get("name") in out:
            errors.append(f"{path}: job name {m.get('name')!r} repeated")
        check_job(path, m, os.path.dirname(os.path.abspath(path)), errors)
        out[m.get("name")] = m
    return out


def resolved(job, base):
    """The job with its input paths absolute (to compare jobs of files in different folders)."""
    out = dict(job)
    if "input" in job:
        out["input"] = os.path.normpath(os.path.join(base, job["input"]))
    if "bodies" in job:
        out["bodies"] = [dict(b, input=os.path.normpath(os.path.join(base, b["input"]))) for b in job["bodies"]]
    return out


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    files = argv or sorted(glob.glob(os.path.join(here, "**", "*.yaml"), recursive=True))
    errors = []
    loaded = {}
    for path in files:
        loaded[os.path.abspath(path)] = load_jobs(path, errors)
        print(f"{os.path.relpath(path)}: {len(loaded[os.path.abspath(path)])} job(s)")
    all_path = os.path.join(here, "all.yaml")
    if all_path in loaded:
        others = {}
        for p, jobs in loaded.items():
            if p != all_path:
                for n, j in jobs.items():
                    others[n] = (p, j)
        for n, j in loaded[all_path].items():
            if n not in others:
                errors.append(f"all.yaml: job {n!r} is in no per-model file")
                continue
            p, o = others[n]
            a, b = resolved(j, here), resolved(o, os.path.dirname(p))
            if a != b:
                diff = sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))
                errors.append(f"all.yaml: job {n!r} differs from {os.path.relpath(p)} in {diff}")
    for e in errors:
        print(f"ERROR {e}")
    print("configs OK" if not errors else f"{len(errors)} error(s)")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

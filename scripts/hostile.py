#!/usr/bin/env python3
"""Hostile inputs against the `obscura` binary: a review of issue 21's classes.

Writes several hundred malformed, extreme and malicious scene files and argument lists
into a temporary folder, runs the CLI on each under a timeout and an address-space
limit, and counts what the rules forbid:

- panic: a Rust panic (exit 101 or "panicked" on stderr);
- abort: SIGABRT or "memory allocation ... failed";
- slow: a run over 10 s on an input under 10 MB;
- outside-read: a file outside the scene's folder opened (traced with strace when it
  is installed; without it, a canary file that would load is the witness);
- input-overwritten: a file the load read changed by the run;
- tmp-left: a `.NAME.obscura-PID.tmp` file left behind;
- silent-wrong: exit 0 with an empty picture (or a picture an exact algorithm draws
  differently from the z-buffer) and no warning;
- unnamed-error: an error that does not name the file (or flag) it is about;
- debug-text: an error that prints Rust debug structures.

Usage: scripts/hostile.py [--bin target/release/obscura] [--classes reads,writes,...]
[--seed N] [--keep]. Prints one line per finding and a table per class; exits 1 when
anything was found. Python 3.8+, no packages.
"""

import argparse
import hashlib
import json
import math
import os
import random
import resource
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time

MEM_LIMIT = 8 << 30  # address space per run; an abort under it is a finding
TIMEOUT = 30.0
SLOW = 10.0

findings = []
counts = {}


def note(cls, kind, case, detail=""):
    detail = " | ".join(line.strip() for line in str(detail).splitlines() if line.strip())
    findings.append((cls, kind, case, detail))
    print(f"FINDING [{cls}] {kind}: {case} {detail}".rstrip(), flush=True)


def limit():
    resource.setrlimit(resource.RLIMIT_AS, (MEM_LIMIT, MEM_LIMIT))
    # A background job of a non-interactive shell starts with SIGINT ignored; the runs
    # get the default disposition a user's terminal gives them.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


class Run:
    def __init__(self, rc, secs, out, err, rss_mb, opened):
        self.rc, self.secs, self.out, self.err, self.rss_mb = rc, secs, out, err, rss_mb
        self.opened = opened


def run(bin_, args, cwd, trace=False, timeout=TIMEOUT):
    cmd = [bin_] + args
    trace_file = None
    if trace and shutil.which("strace"):
        trace_file = os.path.join(cwd, ".trace")
        cmd = ["strace", "-f", "-qq", "-e", "trace=open,openat,openat2,stat,newfstatat,readlink",
               "-o", trace_file] + cmd
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         stdin=subprocess.DEVNULL, preexec_fn=limit)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        out, err = p.communicate()
    secs = time.monotonic() - t0
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    opened = []
    if trace_file and os.path.exists(trace_file):
        with open(trace_file, errors="replace") as f:
            for line in f:
                if "open" in line and "ENOENT" not in line:
                    start = line.find('"')
                    end = line.find('"', start + 1)
                    if start >= 0 and end > start:
                        opened.append(line[start + 1:end])
        os.remove(trace_file)
    return Run(p.returncode, secs, out.decode(errors="replace"), err.decode(errors="replace"),
               ru.ru_maxrss / 1024, opened)


# Cases ended by the time limit (reported, not findings).
TIME_LIMITED = []


def common_checks(cls, case, r, size_bytes=0, names=()):
    """The checks every run gets; returns True when the run was clean of them."""
    ok = True
    if r.rc == 101 or "panicked" in r.err:
        note(cls, "panic", case, r.err.strip().splitlines()[-1] if r.err.strip() else "")
        ok = False
    if r.rc in (-6, 134) or "memory allocation of" in r.err:
        note(cls, "abort", case, f"rc={r.rc}")
        ok = False
    if r.rc in (-9,) or r.secs >= TIMEOUT:
        note(cls, "hang", case, f"{r.secs:.1f}s")
        ok = False
    elif r.secs > SLOW and size_bytes < 10_000_000:
        note(cls, "slow", case, f"{r.secs:.1f}s")
        ok = False
    if r.rc not in (0, 101, -6, 134, -9):
        err = r.err.strip()
        # A run stopped or refused by the time limit names the work and --time-limit
        # (and, for a file, the file): a named reason whatever the case expected.
        timed = "--time-limit" in err
        if timed:
            TIME_LIMITED.append(case)
        if names and not timed and not any(n in err for n in names):
            note(cls, "unnamed-error", case, err[:160])
            ok = False
        # (A control character quoted as `\u{12}` is an escape, not a debug structure.)
        for artefact in ("Some(", "None)", "Err(", "Ok(", "{ kind:", "Error {"):
            if artefact in err:
                note(cls, "debug-text", case, err[:160])
                ok = False
                break
    return ok


def sha(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(path, mode) as f:
        f.write(data)


TRI_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
CUBE_OBJ = """mtllib cube.mtl
v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
usemtl red
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
"""
MTL = "newmtl red\nKd 1 0 0\n"
TRI_BIN = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)


def gltf_json(uri, image_uri=None):
    d = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"uri": uri, "byteLength": 36}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
    }
    if image_uri is not None:
        d["images"] = [{"uri": image_uri}]
        d["textures"] = [{"source": 0}]
        d["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
        d["meshes"][0]["primitives"][0]["material"] = 0
    return json.dumps(d)


def data_uri(b):
    import base64
    return "data:application/octet-stream;base64," + base64.b64encode(b).decode()


# ---------------------------------------------------------------- class 1: reads
def reference_forms(canary_dir, name, scene_dir):
    """Ways of spelling a file outside the scene's folder."""
    abs_ = os.path.join(canary_dir, name)
    rel = os.path.relpath(abs_, scene_dir)
    forms = [
        abs_, "/" + abs_.lstrip("/").replace("/", "//"), rel, "./" + rel, "sub/../" + rel,
        "file://" + abs_, "file:" + abs_, "FILE://" + abs_, "file://localhost" + abs_,
        rel.replace("/", "\\"), abs_ + "/.", os.path.join(abs_ + "_dir", "..", name),
        "link_" + name, "linkdir/" + name, "./linkdir/../linkdir/" + name,
        "http://127.0.0.1:9/" + name, "https://example.invalid/" + name,
        "ftp://example.invalid/" + name, "C:/Windows/" + name, "\\\\server\\share\\" + name,
        "~/" + name, "%2e%2e/" + rel.split("/", 1)[-1] if rel.startswith("..") else rel,
        rel.replace("..", "%2E%2E"), abs_.replace("/", "%2F"),
    ]
    return forms


def setup_links(scene_dir, canary_dir, name):
    for link, target in (("link_" + name, os.path.join(canary_dir, name)),
                         ("linkdir", canary_dir)):
        p = os.path.join(scene_dir, link)
        if not os.path.lexists(p):
            os.symlink(target, p)
    os.makedirs(os.path.join(scene_dir, "sub"), exist_ok=True)


def class_reads(bin_, root, rng):
    cls = "reads"
    n = 0
    canary = os.path.join(root, "canary")
    write(os.path.join(canary, "c.bin"), TRI_BIN)
    write(os.path.join(canary, "c.obj"), TRI_OBJ)
    write(os.path.join(canary, "c.mtl"), MTL)
    write(os.path.join(canary, "c.png"), b"\x89PNG\r\n\x1a\n")
    write(os.path.join(canary, "c.stl"), "solid c\nfacet normal 0 0 1\nouter loop\n"
          "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid c\n")
    os.makedirs(os.path.join(canary, "c.bin_dir"), exist_ok=True)
    for kind in ("gltf-buffer", "gltf-image", "obj-mtllib", "toml-mesh", "toml-mesh-stl",
                 "toml-gltf-buffer"):
        name = {"gltf-buffer": "c.bin", "gltf-image": "c.png", "obj-mtllib": "c.mtl",
                "toml-mesh": "c.obj", "toml-mesh-stl": "c.stl",
                "toml-gltf-buffer": "c.bin"}[kind]
        for i, ref in enumerate(reference_forms(canary, name, os.path.join(root, "s"))):
            for allow in (False, True):
                d = os.path.join(root, f"r_{kind}_{i}_{int(allow)}")
                os.makedirs(d)
                setup_links(d, canary, name)
                ref2 = ref.replace(os.path.join(root, "s"), d)
                if kind == "gltf-buffer":
                    scene = os.path.join(d, "a.gltf")
                    write(scene, gltf_json(ref2))
                elif kind == "gltf-image":
                    scene = os.path.join(d, "a.gltf")
                    write(scene, gltf_json(data_uri(TRI_BIN), ref2))
                elif kind == "obj-mtllib":
                    scene = os.path.join(d, "a.obj")
                    write(scene, f"mtllib {ref2}\n" + TRI_OBJ.replace("f ", "usemtl red\nf "))
                elif kind in ("toml-mesh", "toml-mesh-stl"):
                    scene = os.path.join(d, "a.toml")
                    write(scene, f"[[object]]\nmesh = {json.dumps(ref2)}\n")
                else:
                    scene = os.path.join(d, "a.toml")
                    write(os.path.join(d, "m", "b.gltf"), gltf_json("../" + ref2
                          if not os.path.isabs(ref2) and "://" not in ref2 else ref2))
                    write(scene, "[[object]]\nmesh = \"m/b.gltf\"\n")
                args = ["render", scene, "--size", "32x24", "-o", os.path.join(d, "o.png")]
                if allow:
                    args.append("--allow-outside-references")
                r = run(bin_, args, d, trace=True)
                n += 1
                case = f"{kind} ref={ref2!r} allow={allow}"
                common_checks(cls, case, r, names=(os.path.basename(scene), "b.gltf"))
                touched = [p for p in r.opened if p.startswith(canary)]
                if not allow and touched:
                    note(cls, "outside-read", case, f"opened {touched[0]}")
                local = not ref2.startswith(("http:", "https:", "ftp:"))
                if not allow and r.rc != 0 and local and "allow-outside-references" \
                        not in r.err and "No such file" not in r.err:
                    note(cls, "no-flag-hint", case, r.err.strip()[:160])
                if not allow and r.rc == 0 and shutil.which("strace") is None \
                        and kind != "gltf-image":
                    note(cls, "outside-read", case, "loaded the canary")
    # data: URIs keep working
    for i in range(20):
        d = os.path.join(root, f"r_data_{i}")
        scene = os.path.join(d, "a.gltf")
        write(scene, gltf_json(data_uri(TRI_BIN)))
        r = run(bin_, ["render", scene, "--size", "32x24", "-o", os.path.join(d, "o.png")], d)
        n += 1
        common_checks(cls, f"data-uri {i}", r, names=("a.gltf",))
        if r.rc != 0:
            note(cls, "data-uri-refused", f"data-uri {i}", r.err.strip()[:160])
    counts[cls] = n


# ---------------------------------------------------------------- class 2: writes
KIND_EXT = {"-o": ".png", "--ids": ".npy", "--depth": ".npy", "--stats-json": ".json",
            "--json": ".json"}

def class_writes(bin_, root, rng):
    cls = "writes"
    n = 0
    base = os.path.join(root, "w")
    sets = {
        "obj": {"a.obj": CUBE_OBJ, "cube.mtl": MTL},
        "toml": {"a.toml": "[[object]]\nmesh = \"m/cube.obj\"\n[[object]]\nmesh = \"t.stl\"\n"
                 "[[object]]\nmesh = \"g.gltf\"\ntranslate = [3, 0, 0]\n",
                 "m/cube.obj": CUBE_OBJ, "m/cube.mtl": MTL,
                 "t.stl": "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 2\n"
                 "vertex 1 0 2\nvertex 0 1 2\nendloop\nendfacet\nendsolid t\n",
                 "g.gltf": gltf_json("g.bin"), "g.bin": TRI_BIN},
        "gltf": {"a.gltf": gltf_json("buf/g.bin"), "buf/g.bin": TRI_BIN},
    }
    flags = {"render": ["-o", "--ids", "--depth", "--stats-json"],
             "compare": ["-o", "--json"]}
    for set_name, files in sets.items():
        scene_name = next(f for f in files if f.startswith("a."))
        for input_name in files:
            for sub, fl in flags.items():
                for flag in fl:
                    for spelling in ("plain", "dot", "abs", "updown", "symlink", "hardlink",
                                     "upper-ext"):
                        d = os.path.join(base, f"{set_name}_{input_name.replace('/', '_')}_"
                                         f"{sub}_{flag.strip('-')}_{spelling}")
                        for f, c in files.items():
                            write(os.path.join(d, f), c)
                        hashes = {f: sha(os.path.join(d, f)) for f in files}
                        target = input_name
                        if spelling == "dot":
                            target = "./" + input_name
                        elif spelling == "abs":
                            target = os.path.join(d, input_name)
                        elif spelling == "updown":
                            target = os.path.join("m", "..", input_name)
                            os.makedirs(os.path.join(d, "m"), exist_ok=True)
                        elif spelling == "symlink":
                            target = "link" + KIND_EXT[flag]
                            os.symlink(input_name, os.path.join(d, target))
                        elif spelling == "hardlink":
                            target = "hard" + KIND_EXT[flag]
                            os.link(os.path.join(d, input_name), os.path.join(d, target))
                        elif spelling == "upper-ext":
                            continue
                        args = [sub, scene_name, "--size", "32x24", flag, target]
                        if sub == "compare":
                            args += ["--algos", "zbuffer,raycast-bvh"]
                            if flag != "-o":
                                args += ["-o", "grid.png"]
                        for force in (False, True):
                            a2 = args + (["--force-extension"] if force else [])
                            r = run(bin_, a2, d)
                            n += 1
                            case = f"{set_name}: {sub} {flag} {target} (input {input_name})" \
                                   f"{' forced' if force else ''}"
                            common_checks(cls, case, r, names=(flag, target, input_name,
                                                               os.path.basename(target)))
                            for f, h in hashes.items():
                                if sha(os.path.join(d, f)) != h:
                                    note(cls, "input-overwritten", case, f)
                                    write(os.path.join(d, f), files[f])
                            if r.rc == 0:
                                note(cls, "input-output-accepted", case)
                            left = [x for x in os.listdir(d) if x.endswith(".tmp")]
                            if left:
                                note(cls, "tmp-left", case, left[0])
    # Outputs of the wrong kind are refused unless forced.
    d = os.path.join(base, "kinds")
    write(os.path.join(d, "a.obj"), CUBE_OBJ)
    write(os.path.join(d, "cube.mtl"), MTL)
    wrong = {"-o": ["x.npy", "x.json", "x.txt", "x", "x.PNG.bak"],
             "--ids": ["x.png", "x.json", "x.txt"], "--depth": ["x.png", "x"],
             "--stats-json": ["x.npy", "x.png", "x.txt"]}
    for flag, names in wrong.items():
        for name in names:
            r = run(bin_, ["render", "a.obj", "--size", "32x24", flag, name], d)
            n += 1
            case = f"render {flag} {name}"
            common_checks(cls, case, r, names=(flag, name))
            if r.rc == 0:
                note(cls, "wrong-kind-accepted", case)
            r = run(bin_, ["render", "a.obj", "--size", "32x24", flag, name,
                           "--force-extension"], d)
            n += 1
            if r.rc != 0:
                note(cls, "forced-kind-refused", case, r.err.strip()[:160])
            for x in os.listdir(d):
                if x.startswith("x"):
                    os.remove(os.path.join(d, x))
    # Signals: no temporary file left, earlier outputs intact.
    d = os.path.join(base, "signals")
    os.makedirs(d)
    write(os.path.join(d, "old.png"), b"earlier output")
    h = sha(os.path.join(d, "old.png"))
    for i in range(24):
        sig = (signal.SIGINT, signal.SIGTERM)[i % 2]
        delay = rng.uniform(0.05, 1.5)
        p = subprocess.Popen([bin_, "render", "demo:sphere", "--algo",
                              rng.choice(["depth-sort", "warnock", "raycast", "scanline"]),
                              "--size", "1920x1080", "-o", "old.png", "--ids", "ids.npy"],
                             cwd=d, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                             preexec_fn=limit)
        time.sleep(delay)
        p.send_signal(sig)
        try:
            _, err = p.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            p.kill()
            _, err = p.communicate()
            note(cls, "hang", f"signal {sig.name} after {delay:.2f}s", "did not stop")
        n += 1
        case = f"{sig.name} after {delay:.2f}s"
        left = [x for x in os.listdir(d) if x.endswith(".tmp")]
        if left:
            note(cls, "tmp-left", case, left[0])
            for x in left:
                os.remove(os.path.join(d, x))
        if os.path.exists(os.path.join(d, "old.png")) and p.returncode != 0 \
                and sha(os.path.join(d, "old.png")) != h:
            note(cls, "earlier-output-damaged", case)
        if p.returncode == 0:
            write(os.path.join(d, "old.png"), b"earlier output")
        if b"panicked" in err:
            note(cls, "panic", case)
    counts[cls] = n


# ---------------------------------------------------------------- class 3: resources
def big_triangles_obj(path, n, rng, spread=10.0):
    lines = []
    for _ in range(n):
        for _ in range(3):
            lines.append("v %.6f %.6f %.6f" % tuple(rng.uniform(-spread, spread)
                                                    for _ in range(3)))
    for i in range(n):
        lines.append(f"f {3 * i + 1} {3 * i + 2} {3 * i + 3}")
    write(path, "\n".join(lines) + "\n")


def class_resources(bin_, root, rng):
    cls = "resources"
    n = 0
    d = os.path.join(root, "res")
    os.makedirs(d)
    for tris in (2000, 5000, 20000):
        big_triangles_obj(os.path.join(d, f"big{tris}.obj"), tris, rng)
    algos = ["zbuffer", "scanline", "depth-sort", "depth-sort-matrix", "bsp", "warnock",
             "raycast-bounds", "raycast-bvh", "raycast-grid", "octree"]
    for tris in (2000, 5000, 20000):
        for algo in algos:
            for size in (("160x120", "640x480") if tris == 5000 else ("160x120",)):
                scene = f"big{tris}.obj"
                r = run(bin_, ["render", scene, "--algo", algo, "--size", size, "-o",
                               "o.png"], d)
                n += 1
                case = f"render {scene} --algo {algo} --size {size}"
                common_checks(cls, case, r, os.path.getsize(os.path.join(d, scene)),
                              names=(scene, "memory", "budget", "limit"))
                if r.rc != 0 and not any(w in r.err for w in ("memory", "budget", "limit")):
                    note(cls, "refused-without-budget-reason", case, r.err.strip()[:160])
        r = run(bin_, ["compare", f"big{tris}.obj", "--size", "160x120", "-o", "g.png",
                       "--json", "c.json"], d)
        n += 1
        case = f"compare big{tris}.obj"
        common_checks(cls, case, r, names=(f"big{tris}.obj",))
        if r.rc != 0:
            note(cls, "compare-gave-up", case, r.err.strip()[:160])
    for depth in range(6, 12):
        for scene in ("big5000.obj", "demo:triangles", "demo:sphere"):
            r = run(bin_, ["render", scene, "--algo", "octree", "--octree-depth", str(depth),
                           "--size", "160x120", "-o", "o.png"], d)
            n += 1
            common_checks(cls, f"octree depth {depth} {scene}", r, names=("octree",))
    for limit_ in ("1M", "16M", "64M", "100000", "1G"):
        for algo in algos:
            r = run(bin_, ["render", "big5000.obj", "--algo", algo, "--size", "640x480",
                           "--memory-limit", limit_, "-o", "o.png"], d)
            n += 1
            case = f"{algo} --memory-limit {limit_}"
            common_checks(cls, case, r, names=("memory", "--memory-limit"))
    for k in (1000, 10000, 100000):
        lines = [f"[[object]]\nmesh = \"big2000.obj\"\ntranslate = [{i % 100}, {i // 100}, 0]"
                 for i in range(k)]
        scene = os.path.join(d, f"inst{k}.toml")
        write(scene, "\n".join(lines) + "\n")
        r = run(bin_, ["render", f"inst{k}.toml", "--size", "160x120", "-o", "o.png"], d)
        n += 1
        common_checks(cls, f"instancing {k}", r, os.path.getsize(scene), names=(f"inst{k}",))
        for prim, extra in (("sphere", "segments = 20000\nrings = 10000"),
                            ("grid", "nx = 100000\nnz = 100000"),
                            ("torus", "segments = 4000\nrings = 4000")):
            lines = [f"[[object]]\nprimitive = \"{prim}\"\n{extra}" for _ in range(k // 100)]
            scene = os.path.join(d, f"prim{prim}{k}.toml")
            write(scene, "\n".join(lines) + "\n")
            r = run(bin_, ["render", os.path.basename(scene), "--size", "160x120", "-o",
                           "o.png"], d)
            n += 1
            common_checks(cls, f"primitives {prim} x{k // 100}", r, os.path.getsize(scene),
                          names=(os.path.basename(scene),))
    for size in ("16384x16384", "16384x1", "1x16384", "100000x100000", "0x10", "99999999999x2"):
        for scene in ("demo:cube", "big2000.obj"):
            r = run(bin_, ["render", scene, "--size", size, "-o", "o.png", "--algo",
                           rng.choice(algos)], d)
            n += 1
            common_checks(cls, f"size {size} {scene}", r, names=("size", "--size"))
    # A PLY of many large overlapping triangles.
    m = 400_000
    hdr = (f"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
           f"property float y\nproperty float z\nelement face {m}\n"
           f"property list uchar int vertex_indices\nend_header\n").encode()
    verts = struct.pack("<9f", -100, -100, 0, 100, -100, 0, 0, 100, 0)
    face = struct.pack("<B3i", 3, 0, 1, 2)
    write(os.path.join(d, "many.ply"), hdr + verts + face * m)
    for algo in algos:
        r = run(bin_, ["render", "many.ply", "--algo", algo, "--size", "320x240", "-o",
                       "o.png"], d)
        n += 1
        common_checks(cls, f"many.ply {algo}", r, os.path.getsize(os.path.join(d, "many.ply")),
                      names=("many.ply", "memory"))
    counts[cls] = n


# ---------------------------------------------------------------- class 4: linear time
def class_linear(bin_, root, rng):
    cls = "linear"
    n = 0
    d = os.path.join(root, "lin")
    os.makedirs(d)
    facet = ("facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
             "endloop\nendfacet\n")
    shapes = {
        "solids.stl": lambda k: "".join(f"solid s{i}\n{facet}endsolid s{i}\n"
                                        for i in range(k)),
        "upper.stl": lambda k: "".join(f"SOLID S{i}\n{facet.upper()}ENDSOLID S{i}\n"
                                       for i in range(k)),
        "facets.stl": lambda k: "solid a\n" + facet * k + "endsolid a\n",
        "elements.ply": lambda k: "ply\nformat ascii 1.0\n" + "".join(
            f"element e{i} 0\nproperty float x\n" for i in range(k)) +
            "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        "comments.ply": lambda k: "ply\nformat ascii 1.0\n" + "comment x\n" * k +
            "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        "props.ply": lambda k: "ply\nformat ascii 1.0\nelement vertex 3\n" + "".join(
            f"property float p{i}\n" for i in range(k)) + "property float x\n"
            "property float y\nproperty float z\nelement face 1\n"
            "property list uchar int vertex_indices\nend_header\n" +
            ("0 " * k + "0 0 0\n") + ("0 " * k + "1 0 0\n") + ("0 " * k + "0 1 0\n") +
            "3 0 1 2\n",
        "objects.obj": lambda k: "v 0 0 0\nv 1 0 0\nv 0 1 0\n" + "".join(
            f"o o{i}\nf 1 2 3\n" for i in range(k)),
        "groups.obj": lambda k: "v 0 0 0\nv 1 0 0\nv 0 1 0\n" + "".join(
            f"g g{i}\nusemtl m{i}\nf 1 2 3\n" for i in range(k)),
        "negidx.obj": lambda k: "".join("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"
                                        for _ in range(k)),
        "bigface.obj": lambda k: "".join(f"v {i} {(i * 7919) % 1000 / 1000.0} 0\n"
                                         for i in range(k)) + "f " + " ".join(
            str(i + 1) for i in range(k)) + "\n",
        "materials.obj": lambda k: "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n" + "".join(
            f"usemtl m{i % 1000}\nf 1 2 3\n" for i in range(k)),
        "objects.toml": lambda k: "".join(
            f"[[object]]\nprimitive = \"box\"\ntranslate = [{i}, 0, 0]\n" for i in range(k)),
        "meshes.toml": lambda k: "".join(
            f"[[object]]\nmesh = \"t.obj\"\ntranslate = [{i}, 0, 0]\n" for i in range(k)),
    }
    write(os.path.join(d, "t.obj"), TRI_OBJ)
    write(os.path.join(d, "m.mtl"), "".join(f"newmtl m{i}\nKd 1 0 0\n" for i in range(1000)))
    for name, make in shapes.items():
        times = {}
        for k in (2_000, 8_000, 32_000, 128_000):
            text = make(k)
            if len(text) > 10_000_000:
                continue
            path = os.path.join(d, name)
            write(path, text)
            r = run(bin_, ["render", name, "--size", "32x24", "-o", "o.png"], d)
            n += 1
            case = f"{name} x{k} ({len(text) / 1e6:.1f} MB)"
            common_checks(cls, case, r, len(text), names=(name,))
            times[k] = r.secs
        ks = sorted(times)
        if len(ks) >= 2 and times[ks[-1]] > 1.0:
            ratio = times[ks[-1]] / max(times[ks[-2]], 1e-3)
            if ratio > 8:
                note(cls, "superlinear", name, f"x4 items took x{ratio:.1f} time")
    # glTF with many nodes, meshes and accessors.
    for k in (1000, 10000, 50000):
        dd = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": list(range(k))}],
              "nodes": [{"mesh": 0, "translation": [i, 0, 0]} for i in range(k)],
              "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
              "buffers": [{"uri": data_uri(TRI_BIN), "byteLength": 36}],
              "bufferViews": [{"buffer": 0, "byteLength": 36}],
              "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3,
                             "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}]}
        write(os.path.join(d, "nodes.gltf"), json.dumps(dd))
        r = run(bin_, ["render", "nodes.gltf", "--size", "32x24", "-o", "o.png"], d)
        n += 1
        common_checks(cls, f"gltf nodes x{k}", r, names=("nodes.gltf",))
        chain = dict(dd)
        chain["nodes"] = [{"children": [i + 1]} for i in range(k - 1)] + [{"mesh": 0}]
        chain["scenes"] = [{"nodes": [0]}]
        write(os.path.join(d, "chain.gltf"), json.dumps(chain))
        r = run(bin_, ["render", "chain.gltf", "--size", "32x24", "-o", "o.png"], d)
        n += 1
        common_checks(cls, f"gltf node chain depth {k}", r, names=("chain.gltf",))
    counts[cls] = n


# ---------------------------------------------------------------- class 5: numbers
def unit_box_obj(offset, scale):
    o, s = offset, scale
    lines = []
    for z in (0, 1):
        for y in (0, 1):
            for x in (0, 1):
                lines.append("v %r %r %r" % (o + s * x, o + s * y, o + s * z))
    faces = ["1 3 4 2", "5 6 8 7", "1 2 6 5", "2 4 8 6", "4 3 7 8", "3 1 5 7"]
    return "\n".join(lines + ["f " + f for f in faces]) + "\n"


def class_numbers(bin_, root, rng):
    cls = "numbers"
    n = 0
    d = os.path.join(root, "num")
    os.makedirs(d)
    cases = [(10.0 ** k, 1.0) for k in range(0, 31, 2)] + \
            [(0.0, 10.0 ** -k) for k in range(0, 310, 20)] + \
            [(0.0, 10.0 ** k) for k in range(0, 31, 5)] + \
            [(-(10.0 ** k), 10.0 ** (k - 6)) for k in range(0, 31, 3)]
    for off, sc in cases:
        name = f"box_{off:g}_{sc:g}.obj".replace("+", "")
        write(os.path.join(d, name), unit_box_obj(off, sc))
        r = run(bin_, ["compare", name, "--size", "64x48", "-o", "g.png", "--json", "c.json"], d)
        n += 1
        case = f"box offset {off:g} scale {sc:g}"
        common_checks(cls, case, r, names=(name,))
        if r.rc == 0:
            warned = "warning" in r.err.lower()
            try:
                table = json.load(open(os.path.join(d, "c.json")))
            except Exception:
                note(cls, "no-json", case)
                continue
            for a in table.get("algorithms", []):
                agree = a.get("agree_percent")
                if agree is None:
                    continue
                exact = a["algorithm"] != "octree"
                if (exact and agree < 99.0 or not exact and agree < 90.0) and not warned:
                    note(cls, "silent-wrong", case, f"{a['algorithm']} agrees {agree:.1f}%")
            r2 = run(bin_, ["render", name, "--size", "64x48", "-o", "o.png", "--ids",
                            "ids.npy"], d)
            n += 1
            if r2.rc == 0:
                with open(os.path.join(d, "ids.npy"), "rb") as f:
                    raw = f.read()
                hl = struct.unpack("<H", raw[8:10])[0]
                ids = struct.unpack(f"<{64 * 48}i", raw[10 + hl:])
                if all(i == -1 for i in ids) and "warning" not in r2.err.lower():
                    note(cls, "silent-empty", case)
    # Cameras and transforms at extremes.
    write(os.path.join(d, "t.obj"), TRI_OBJ)
    for flags in (["--up", "1e308,0,0"], ["--up", "1e-308,1e-308,0"], ["--eye", "1e300,0,0"],
                  ["--eye", "0,0,1e-300", "--target", "0,0,0"], ["--fov", "1e-300"],
                  ["--fov", "179.9999999"], ["--near", "1e-300"], ["--far", "1e300"],
                  ["--ortho", "1e-300"], ["--ortho", "1e300"], ["--near", "5", "--far", "5"],
                  ["--eye", "nan,0,0"], ["--eye", "inf,0,0"], ["--target", "0,0,-1e308"]):
        r = run(bin_, ["render", "t.obj", "--size", "64x48", "-o", "o.png"] + flags, d)
        n += 1
        common_checks(cls, " ".join(flags), r, names=(flags[0], flags[0].strip("-"),
                                                      "field of view", "camera"))
    for scale in ("1e200", "1e-200", "1e308", "1e-320", "[1e200, 1, 1]", "0", "-0.0", "nan"):
        write(os.path.join(d, "s.toml"), f"[[object]]\nmesh = \"t.obj\"\n\nscale = {scale}\n")
        r = run(bin_, ["render", "s.toml", "--size", "64x48", "-o", "o.png"], d)
        n += 1
        case = f"toml scale {scale}"
        common_checks(cls, case, r, names=("s.toml",))
        if r.rc != 0 and "s.toml:4" not in r.err:
            note(cls, "wrong-line", case, r.err.strip()[:160])
    counts[cls] = n


# ---------------------------------------------------------------- class 6: messages
def mutate(data, rng):
    b = bytearray(data)
    for _ in range(rng.randint(1, 8)):
        op = rng.random()
        if op < 0.3 and b:
            b[rng.randrange(len(b))] = rng.randrange(256)
        elif op < 0.5 and b:
            del b[rng.randrange(len(b)):]
        elif op < 0.7:
            i = rng.randrange(len(b) + 1)
            b[i:i] = rng.choice([b"nan", b"1e999", b"-", b"\x00", b"\n", b"9" * 30, b"#",
                                 b"-1", b"4294967296", b" ", b"\xff\xfe"])
        elif b:
            i = rng.randrange(len(b))
            j = min(len(b), i + rng.randint(1, 20))
            b[i:i] = b[i:j]
    return bytes(b)


def class_messages(bin_, root, rng):
    cls = "messages"
    n = 0
    d = os.path.join(root, "msg")
    os.makedirs(d)
    ply_ascii = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                 "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").encode()
    stl_bin = b"\0" * 80 + struct.pack("<I", 1) + struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0,
                                                               0, 0, 1, 0, 0)
    glb_json = gltf_json(data_uri(TRI_BIN)).encode()
    glb_json += b" " * ((4 - len(glb_json) % 4) % 4)
    glb = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(glb_json)) + \
        struct.pack("<I4s", len(glb_json), b"JSON") + glb_json
    seeds = {"a.obj": CUBE_OBJ.replace("mtllib cube.mtl\n", "").encode(),
             "a.ply": ply_ascii, "a.stl": stl_bin,
             "b.stl": b"solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n"
                      b"   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n",
             "a.gltf": gltf_json(data_uri(TRI_BIN)).encode(), "a.glb": glb,
             "a.toml": b"[camera]\neye = [3, 3, 3]\ntarget = [0, 0, 0]\n[[object]]\n"
                       b"primitive = \"box\"\nsize = [1, 2, 3]\n[[object]]\nmesh = \"t.obj\"\n"
                       b"matrix = [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n"}
    write(os.path.join(d, "t.obj"), TRI_OBJ)
    for name, data in seeds.items():
        for i in range(60):
            bad = mutate(data, rng)
            fname = f"m{i}_{name}"
            write(os.path.join(d, fname), bad)
            r = run(bin_, ["render", fname, "--size", "32x24", "-o", "o.png"], d)
            n += 1
            common_checks(cls, f"mutated {name} #{i}", r, len(bad), names=(fname,))
            os.remove(os.path.join(d, fname))
    bad_args = [["--size", "-5x5"], ["--size", "5x-5"], ["--size", "0x0"], ["--size", "ax5"],
                ["--size", "1e3x5"], ["--threads", "0"], ["--threads", "-1"],
                ["--threads", "99999"], ["--fov", "-5"], ["--fov", "nan"], ["--fov", "1e-300"],
                ["--near", "-1"], ["--far", "0"], ["--ortho", "-2"], ["--ortho", "3", "--fov",
                                                                         "60"],
                ["--eye", "1,2"], ["--eye", "1,2,3,4"], ["--up", "0,0,0"], ["--algo", "zbufer"],
                ["--octree-depth", "-1"], ["--octree-depth", "99"], ["--bounds", "cube"],
                ["--memory-limit", "-5"], ["--memory-limit", "5X"], ["--memory-limit", "0"]]
    for args in bad_args:
        r = run(bin_, ["render", "t.obj", "-o", "o.png"] + args, d)
        n += 1
        case = " ".join(args)
        common_checks(cls, case, r, names=(args[0], args[0].lstrip("-"), "field of view"))
        if "-- -" in r.err or "tip:" in r.err and "--" in r.err and args[1].startswith("-"):
            note(cls, "clap-hint", case, r.err.strip().splitlines()[0][:120])
        if len(max(r.err.split(), key=len, default="")) > 60:
            note(cls, "long-number", case, max(r.err.split(), key=len)[:80])
        if args == ["--ortho", "3", "--fov", "60"] and r.rc == 0 and "fov" not in r.err:
            note(cls, "silently-ignored", case)
        if args == ["--threads", "0"] and "(0 threads)" in r.out + r.err:
            note(cls, "zero-threads", case)
    for budget in ("1e-300", "1e300", "0", "-1", "nan", "inf"):
        r = run(bin_, ["bench", "--budget", budget, "--max-faces", "100", "--algos", "zbuffer"],
                d)
        n += 1
        case = f"bench --budget {budget}"
        common_checks(cls, case, r, names=("--budget", "budget"))
        if len(max((r.err + r.out).split(), key=len, default="")) > 60:
            note(cls, "long-number", case, max((r.err + r.out).split(), key=len)[:80])
    counts[cls] = n


CELLS_OK = """[[object]]
name = "box"
primitive = "box"
size = [0.5, 1, 0.5]
translate = [0.75, 0.5, 0.75]

[[cell]]
name = "west"
min = [0, 0, 0]
max = [2, 3, 2]

[[cell]]
name = "east"
min = [2, 0, 0]
max = [6, 3, 2]

[[portal]]
cells = ["west", "east"]
polygon = [[2, 0, 0.5], [2, 0, 1.5], [2, 2, 1.5], [2, 2, 0.5]]
"""


def class_culling(bin_, root, rng):
    """cull, export and render --cull on hostile cells, walks, cameras and outputs."""
    cls = "culling"
    n = 0
    d = os.path.join(root, "cells")
    os.makedirs(d)
    cells_bad = {
        "off-boundary": CELLS_OK.replace("[[2, 0, 0.5], [2, 0, 1.5]", "[[2.5, 0, 0.5], [2.5, 0, 1.5]"),
        "open-cell": CELLS_OK.replace('min = [2, 0, 0]\nmax = [6, 3, 2]',
                                      'planes = [[1, 0, 0, -6], [-1, 0, 0, 2]]'),
        "nan-portal": CELLS_OK.replace("[2, 2, 1.5]", "[2, nan, 1.5]"),
        "huge": CELLS_OK.replace("max = [6, 3, 2]", "max = [1e300, 3, 2]"),
        "unknown-cell": CELLS_OK.replace('cells = ["west", "east"]', 'cells = ["west", "north"]'),
        "one-cell-portal": CELLS_OK.replace('cells = ["west", "east"]', 'cells = ["west", "west"]'),
        "degenerate-portal": CELLS_OK.replace("[2, 2, 1.5], [2, 2, 0.5]", "[2, 0, 1.5], [2, 0, 0.5]"),
        "many-points": CELLS_OK.replace("[2, 2, 1.5], [2, 2, 0.5]",
                                        ", ".join(["[2, 1, 1]"] * 5000)),
    }
    for name, text in cells_bad.items():
        write(os.path.join(d, f"{name}.toml"), text.encode())
        for args in (["cull", f"{name}.toml", "--method", "all", "--size", "64x48"],
                     ["render", f"{name}.toml", "--cull", "portals", "--size", "64x48",
                      "-o", "o.png"]):
            r = run(bin_, args, d)
            n += 1
            common_checks(cls, f"cells {name}: {args[0]}", r, names=(f"{name}.toml",))
    # A valid model: one closed room holding the box (two rooms would need the wall
    # between them as geometry, or the shared plane is a leak).
    ok = CELLS_OK[:CELLS_OK.index("[[cell]]\nname = \"east\"")]
    write(os.path.join(d, "ok.toml"), ok.encode())
    r = run(bin_, ["cull", "ok.toml", "--method", "all", "--size", "64x48"], d)
    n += 1
    if r.rc != 0:
        note(cls, "valid-cells-refused", "ok.toml", r.err.strip()[:160])
    # Odd cameras for every method: outside every cell, on a portal, at a corner, far.
    eyes = ["-5,1,1", "2,1,1", "0,0,0", "1e12,1,1", "1,1,1", "2,2,0.5"]
    for eye in eyes:
        for ortho in ([], ["--ortho", "3"]):
            r = run(bin_, ["cull", "ok.toml", "--method", "all", "--size", "64x48",
                           "--eye", eye, "--target", "4,1,1"] + ortho, d)
            n += 1
            common_checks(cls, f"cull eye {eye} {ortho}", r, names=("eye", "camera"))
    # Walk files.
    walks = {
        "empty.csv": b"",
        "header.csv": b"eye_x,eye_y,eye_z,target_x,target_y,target_z\n",
        "nan.csv": b"eye_x,eye_y,eye_z,target_x,target_y,target_z\nnan,1,1,4,1,1\n",
        "short.csv": b"eye_x,eye_y,eye_z,target_x,target_y,target_z\n1,1,1\n",
        "same.csv": b"eye_x,eye_y,eye_z,target_x,target_y,target_z\n1,1,1,1,1,1\n",
        "words.csv": b"eye_x,eye_y,eye_z,target_x,target_y,target_z\na,b,c,d,e,f\n",
        "binary.csv": bytes(rng.randrange(256) for _ in range(4000)),
        "long.csv": b"eye_x,eye_y,eye_z,target_x,target_y,target_z\n" + b"1" * 3_000_000 + b"\n",
        "fov.csv": b"eye_x,eye_y,eye_z,target_x,target_y,target_z,fov\n1,1,1,4,1,1,400\n",
    }
    for name, data in walks.items():
        write(os.path.join(d, name), data)
        r = run(bin_, ["cull", "ok.toml", "--method", "all", "--size", "64x48",
                       "--walk", name], d)
        n += 1
        common_checks(cls, f"walk {name}", r, names=(name,))
    # Outputs onto inputs are refused, inputs intact.
    h = sha(os.path.join(d, "ok.toml"))
    for args in (["export", "ok.toml", "-o", "ok.toml"],
                 ["export", "ok.toml", "-o", "ok.toml", "--force-extension"],
                 ["cull", "ok.toml", "--method", "buffer", "--kept", "ok.toml",
                  "--force-extension"],
                 ["cull", "ok.toml", "--method", "buffer", "--explain", "ok.toml",
                  "--force-extension"],
                 ["cull", "ok.toml", "--stats-json", "ok.toml", "--force-extension"]):
        r = run(bin_, args, d)
        n += 1
        case = " ".join(args)
        common_checks(cls, case, r, names=("ok.toml",))
        if sha(os.path.join(d, "ok.toml")) != h:
            note(cls, "input-overwritten", case)
            write(os.path.join(d, "ok.toml"), ok.encode())
        if r.rc == 0:
            note(cls, "input-output-accepted", case)
    # Quake portal files: malformed, lying, huge, NaN, outside the scene's folder.
    r = run(bin_, ["export", "demo:level", "-o", "level.obj"], d)
    n += 1
    common_checks(cls, "export demo:level", r)
    prts = {
        "empty.prt": b"",
        "magic.prt": b"PRT2\n2\n1\n",
        "counts.prt": b"PRT1\n99999999999\n99999999999\n",
        "short.prt": b"PRT1\n2\n1\n4 0 1 (0 0 0 ) (1 0 0 ) (1 1 0 )\n",
        "nan.prt": b"PRT1\n2\n1\n3 0 1 (0 0 0 ) (nan 0 0 ) (1 1 0 )\n",
        "huge.prt": b"PRT1\n2\n1\n3 0 1 (0 0 0 ) (1e300 0 0 ) (1 1e300 0 )\n",
        "leaf.prt": b"PRT1\n2\n1\n3 0 7 (0 0 0 ) (1 0 0 ) (1 1 0 )\n",
        "flat.prt": b"PRT1\n2\n1\n3 0 1 (0 0 0 ) (1 0 0 ) (2 0 0 )\n",
        "binary.prt": bytes(rng.randrange(256) for _ in range(4000)),
        "many.prt": b"PRT1\n2\n1\n5000 0 1 " + b"(0 0 0 ) " * 5000 + b"\n",
    }
    for name, data in prts.items():
        write(os.path.join(d, name), data)
        for args in (["render", "level.obj", "--prt", name, "--cull", "portals",
                      "--size", "64x48", "-o", "o.png"],
                     ["cull", "level.obj", "--prt", name, "--method", "all",
                      "--size", "64x48"]):
            r = run(bin_, args, d)
            n += 1
            common_checks(cls, f"prt {name}: {args[0]}", r, names=(name,))
        write(os.path.join(d, f"prt-{name}.toml"),
              f'prt = "{name}"\n\n[[object]]\nfile = "level.obj"\n'.encode())
        r = run(bin_, ["cull", f"prt-{name}.toml", "--method", "portals", "--size", "64x48"], d)
        n += 1
        common_checks(cls, f"prt key {name}", r, names=(name, f"prt-{name}.toml"))
    # Portal files and occluder meshes outside the scene's folder are refused.
    sub = os.path.join(d, "sub")
    os.makedirs(sub, exist_ok=True)
    write(os.path.join(sub, "out.toml"), b'prt = "../empty.prt"\n')
    write(os.path.join(sub, "occ-out.toml"),
          b'[[object]]\nname = "box"\nprimitive = "box"\nsize = [1, 1, 1]\n'
          b'occluder = "../level.obj"\n')
    for name in ("out.toml", "occ-out.toml"):
        r = run(bin_, ["cull", name, "--method", "all", "--size", "64x48"], sub)
        n += 1
        common_checks(cls, f"outside the folder: {name}", r, names=(name,))
        if r.rc == 0:
            note(cls, "read-outside-folder", name)
    # Occluder meshes: outside their object, NaN, inverted, huge, a missing file.
    occ = {
        "box-out": 'occluder_box = [[-1, -1, -1], [1, 1, 1]]',
        "box-nan": 'occluder_box = [[nan, 0, 0], [0.1, 0.1, 0.1]]',
        "box-inverted": 'occluder_box = [[0.2, 0.2, 0.2], [-0.2, -0.2, -0.2]]',
        "box-huge": 'occluder_box = [[-1e300, 0, 0], [0.1, 0.1, 0.1]]',
        "missing": 'occluder = "nosuch.obj"',
        "garbage": 'occluder = "binary.prt"',
        "both": 'occluder = "level.obj"\noccluder_box = [[0, 0, 0], [0.1, 0.1, 0.1]]',
    }
    for name, key in occ.items():
        text = ('[[object]]\nname = "box"\nprimitive = "box"\nsize = [1, 1, 1]\n'
                + key + "\n")
        write(os.path.join(d, f"occ-{name}.toml"), text.encode())
        for method in ("occluders", "buffer"):
            r = run(bin_, ["cull", f"occ-{name}.toml", "--method", method, "--size", "64x48"], d)
            n += 1
            common_checks(cls, f"occluder {name} {method}", r, names=(f"occ-{name}.toml", "box"))
    # Every demo, every method, small and odd sizes; export of each demo.
    for demo in ("default", "cube", "city", "blocks", "level", "level-grid", "cells5"):
        for size in ("1x1", "64x48", "3x2000"):
            r = run(bin_, ["cull", f"demo:{demo}", "--method", "all", "--size", size], d)
            n += 1
            common_checks(cls, f"cull demo:{demo} {size}", r, names=("size",))
        r = run(bin_, ["export", f"demo:{demo}", "-o", f"{demo}.obj"], d)
        n += 1
        common_checks(cls, f"export demo:{demo}", r)
        r = run(bin_, ["render", f"{demo}.obj", "--cull", "buffer", "--size", "64x48",
                       "-o", "o.png"], d)
        n += 1
        common_checks(cls, f"render exported {demo} --cull buffer", r)
    counts[cls] = n


def class_lines(bin_, root, rng):
    """lines: hostile meshes, height fields, pages, drawings and outputs."""
    cls = "lines"
    n = 0
    d = os.path.join(root, "lines")
    os.makedirs(d)
    write(os.path.join(d, "cube.obj"), CUBE_OBJ)
    write(os.path.join(d, "cube.mtl"), MTL)
    meshes = {
        "nan.obj": b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n",
        "huge.obj": b"v 0 0 0\nv 1e300 0 0\nv 0 1e300 0\nv 0 0 1e300\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n",
        "flat.obj": b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
        "tiny.obj": b"v 0 0 0\nv 1e-300 0 0\nv 0 1e-300 0\nf 1 2 3\n",
        "same.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 3\nf 3 2 1\n",
        "empty.obj": b"",
        "fan.obj": b"v 0 0 0\n" + b"".join(b"v %f %f 0\n" % (math.cos(a / 97.0), math.sin(a / 97.0))
                                          for a in range(600)) +
                   b"".join(b"f 1 %d %d\n" % (i + 2, i + 3) for i in range(598)),
    }
    for name, data in meshes.items():
        write(os.path.join(d, name), data)
        for algo in ("hlr", "roberts"):
            r = run(bin_, ["lines", name, "--algo", algo, "--size", "64x48", "-o", "o.svg",
                           "--check"], d)
            n += 1
            common_checks(cls, f"lines {algo} {name}", r, names=(name, name.split(".")[0]))
    # Height fields.
    fields = {
        "nan.csv": b"1,2\nnan,4\n",
        "ragged.csv": b"1,2,3\n4,5\n",
        "empty.csv": b"",
        "one.csv": b"7\n",
        "words.csv": b"a,b\nc,d\n",
        "long.csv": b",".join([b"1"] * 200000) + b"\n",
        "huge.csv": b"1e308,-1e308\n1e308,1e308\n",
        "bad.npy": b"\x93NUMPY\x01\x00\x20\x00{'descr': '<f8', 'shape': (99999999, 99999999), }\n",
        "short.npy": b"\x93NUMPY\x01\x00\x76\x00{'descr': '<f8', 'fortran_order': False, 'shape': (4, 4), }" + b" " * 50 + b"\n" + b"\x00" * 8,
        "garbage.png": bytes(rng.randrange(256) for _ in range(3000)),
    }
    for name, data in fields.items():
        write(os.path.join(d, name), data)
        r = run(bin_, ["lines", "--algo", "horizon", "--field", name, "--size", "64x48",
                       "-o", "o.svg"], d)
        n += 1
        common_checks(cls, f"field {name}", r, names=(name,))
    for args in (["--function", "nosuch"], ["--function", "ripple", "--grid", "0"],
                 ["--function", "ripple", "--grid", "1000000000"],
                 ["--function", "ripple", "--grid", "3000"],
                 ["--function", "peaks", "--eye", "0,1e300,0"],
                 ["--function", "bumps", "--curves", "both", "--ridgeline"],
                 ["--function", "waves", "--eye", "0,-5,0", "--target", "0,0,0"]):
        r = run(bin_, ["lines", "--algo", "horizon", "--size", "64x48", "-o", "o.svg"] + args, d)
        n += 1
        common_checks(cls, "horizon " + " ".join(args), r,
                      names=("function", "grid", "eye", "field", "view", "camera", "--time-limit"))
    # Pages and numbers.
    for args in (["--page", "A0x"], ["--page", "0x0mm"], ["--page", "1e9x1e9mm"],
                 ["--page", "A4", "--margin", "200"], ["--page", "A4", "--margin", "-1"],
                 ["--stroke", "nan"], ["--stroke", "1e300"], ["--precision", "99"],
                 ["--tolerance", "-1"], ["--min-length", "inf"], ["--crease", "500"],
                 ["--edges", "nosuch"], ["--size", "16384x16384"]):
        r = run(bin_, ["lines", "cube.obj", "-o", "o.svg"] + args, d)
        n += 1
        common_checks(cls, "lines " + " ".join(args), r, names=tuple(a for a in args if a.startswith("--")))
    # Drawings read back.
    drawings = {"d1.json": b"{", "d2.json": b"[]", "d3.json": b'{"width": 1e18, "height": 5, "edges": []}',
                "d4.json": b'{"width": 64, "height": 48, "edges": [{"pieces": "x"}]}'}
    for name, data in drawings.items():
        write(os.path.join(d, name), data)
        r = run(bin_, ["lines", "--drawing", name, "-o", "o.svg", "--png", "o.png"], d)
        n += 1
        common_checks(cls, f"drawing {name}", r, names=(name,))
    # Outputs onto inputs.
    h = sha(os.path.join(d, "cube.obj"))
    for args in (["-o", "cube.obj", "--force-extension"], ["--json", "cube.obj", "--force-extension"],
                 ["--png", "cube.mtl", "--force-extension"]):
        r = run(bin_, ["lines", "cube.obj"] + args, d)
        n += 1
        case = "lines " + " ".join(args)
        common_checks(cls, case, r, names=("cube.obj", "cube.mtl"))
        if sha(os.path.join(d, "cube.obj")) != h:
            note(cls, "input-overwritten", case)
            write(os.path.join(d, "cube.obj"), CUBE_OBJ)
        if r.rc == 0:
            note(cls, "input-output-accepted", case)
    counts[cls] = n


CLASSES = {"reads": class_reads, "writes": class_writes, "resources": class_resources,
           "linear": class_linear, "numbers": class_numbers, "messages": class_messages,
           "culling": class_culling, "lines": class_lines}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(os.path.dirname(__file__), "..", "target",
                                                  "release", "obscura"))
    ap.add_argument("--classes", default=",".join(CLASSES))
    ap.add_argument("--seed", type=int, default=2611)
    ap.add_argument("--keep", action="store_true", help="keep the temporary folder")
    a = ap.parse_args()
    bin_ = os.path.abspath(a.bin)
    if not os.access(bin_, os.X_OK):
        sys.exit(f"{bin_}: not an executable (cargo build --release -p obscura-cli first)")
    root = tempfile.mkdtemp(prefix="obscura-hostile-")
    rng = random.Random(a.seed)
    t0 = time.monotonic()
    try:
        for c in a.classes.split(","):
            t = time.monotonic()
            d = os.path.join(root, c)
            os.makedirs(d)
            CLASSES[c](bin_, d, rng)
            print(f"class {c}: {counts.get(c, 0)} runs, "
                  f"{sum(1 for f in findings if f[0] == c)} findings, "
                  f"{time.monotonic() - t:.0f} s", flush=True)
    finally:
        if not a.keep:
            shutil.rmtree(root, ignore_errors=True)
        else:
            print(f"kept {root}")
    print(f"\n{sum(counts.values())} runs in {time.monotonic() - t0:.0f} s; "
          f"{len(findings)} findings; {len(TIME_LIMITED)} ended by the time limit "
          f"(named, not findings)")
    kinds = {}
    for f in findings:
        kinds[(f[0], f[1])] = kinds.get((f[0], f[1]), 0) + 1
    for (c, k), v in sorted(kinds.items()):
        print(f"  {c:10} {k:28} {v}")
    sys.exit(1 if findings else 0)


if __name__ == "__main__":
    main()

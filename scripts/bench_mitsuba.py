#!/usr/bin/env python3
"""Side-by-side samples/s of ember and Mitsuba 3 (see scripts/bench-mitsuba)."""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_SCENES = ["scenes/cs184/sky/CBspheres_lambertian.dae",
                  "scenes/cs184/sky/CBbunny.dae"]


def cpu_model():
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown CPU"


def ember_run(a, scene, out_dir):
    cmd = [a.ember, "-s", str(a.spp), "-m", str(a.m), "-r", str(a.r[0]), str(a.r[1]),
           "-f", os.path.join(out_dir, "ember.exr")] + a.ember_args.split() + [scene]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"bench-mitsuba: ember failed: {' '.join(cmd)}\n{p.stderr}")
    m = re.search(r"([0-9.]+) M samples/s", p.stderr + p.stdout)
    if not m:
        sys.exit(f"bench-mitsuba: no 'M samples/s' in ember's output:\n{p.stderr}")
    return float(m.group(1)) * 1e6


def mitsuba_run(a, xml, variant, seed):
    cmd = [sys.executable, os.path.join(HERE, "mitsuba-render.py"), xml,
           "--variant", variant, "--renders", "2", "--seed", str(seed)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"bench-mitsuba: Mitsuba failed: {' '.join(cmd)}\n{p.stderr}")
    runs = [json.loads(l) for l in p.stdout.splitlines() if l.startswith("{")]
    return runs[-1]["samples_per_second"]


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--ember", required=True)
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("-m", type=int, default=5)
    p.add_argument("-r", type=int, nargs=2, default=[480, 360])
    p.add_argument("--variants", default="llvm_ad_rgb,scalar_rgb")
    p.add_argument("--scenes", default=",".join(DEFAULT_SCENES))
    p.add_argument("--ember-args", default="", help="extra ember flags, e.g. '--accel embree'")
    p.add_argument("--out", help="also write the rows as CSV here")
    a = p.parse_args()
    if a.rounds < 1:
        sys.exit("bench-mitsuba: --rounds must be at least 1")
    rows = []
    with tempfile.TemporaryDirectory(prefix="ember-mitsuba-") as tmp:
        for scene in a.scenes.split(","):
            name = os.path.splitext(os.path.basename(scene))[0]
            subprocess.run([a.ember, "export", "--format", "mitsuba", scene, "-r", str(a.r[0]),
                            str(a.r[1]), "-s", str(a.spp), "-m", str(a.m), "--out", tmp],
                           check=True, stdout=subprocess.DEVNULL)
            xml = os.path.join(tmp, name + ".xml")
            for variant in a.variants.split(","):
                ember, mitsuba = [], []
                for i in range(a.rounds):
                    ember.append(ember_run(a, scene, tmp))
                    mitsuba.append(mitsuba_run(a, xml, variant, seed=2 * i))
                    print(f"  {name} {variant} round {i + 1}: ember {ember[-1] / 1e6:.2f}, "
                          f"Mitsuba {mitsuba[-1] / 1e6:.2f} M samples/s", file=sys.stderr)
                ratios = [e / m for e, m in zip(ember, mitsuba)]
                rows.append((name, variant, statistics.median(ember), statistics.median(mitsuba),
                             statistics.median(ratios), min(ratios), max(ratios)))
    print(f"CPU: {cpu_model()}, {os.cpu_count()} threads; {a.r[0]}x{a.r[1]}, {a.spp} spp, -m {a.m}, "
          f"{a.rounds} interleaved rounds, render-only medians; ember flags: '{a.ember_args}'")
    print()
    print("| scene | Mitsuba variant | ember M samples/s | Mitsuba M samples/s | ember/Mitsuba (median, min-max of pairs) |")
    print("|---|---|---:|---:|---:|")
    for n, v, e, m, r, lo, hi in rows:
        print(f"| {n} | {v} | {e / 1e6:.2f} | {m / 1e6:.2f} | {r:.2f}x ({lo:.2f}-{hi:.2f}) |")
    if a.out:
        with open(a.out, "w") as f:
            f.write("scene,variant,ember_samples_per_s,mitsuba_samples_per_s,ratio_median,ratio_min,ratio_max\n")
            for row in rows:
                f.write(",".join(str(x) for x in row) + "\n")


if __name__ == "__main__":
    main()

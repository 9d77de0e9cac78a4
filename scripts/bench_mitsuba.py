#!/usr/bin/env python3
"""Side-by-side samples/s of ember and Mitsuba 3 (see scripts/bench-mitsuba).

Scenes: every image of tests/data/references/manifest.json, each at that
reference's max ray depth (-m), then the extra scenes (SCENE.dae:M), by default
the course scenes that have no reference and scenes/cornell.dae. For each scene
and Mitsuba variant, ember and Mitsuba run alternately (ember, Mitsuba, ember,
...), each run in its own process; ember's time is its render-only time (its
summary line), Mitsuba's its second, warm render call (JIT compilation
excluded). The table gives the medians, the median and range of the per-round
ratios, and which engine and estimator ember ran (from its summary line).

Where ember light-traces a scene (`--integrator auto` picks light tracing for
its error per time), Mitsuba's particle tracer (`ptracer`, the same scene file,
spp x pixels light paths like ember's) runs in the same rounds too, and gets a
row of its own: the like-for-like figure beside the path tracer's.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MANIFEST = os.path.join(ROOT, "tests", "data", "references", "manifest.json")
# Issue 23's scenes without a reference, at their own -m, and the first render
# scripts/setup shows a new user.
DEFAULT_EXTRAS = ",".join([
    "scenes/cs184/sky/CBspheres.dae:8",
    "scenes/cs184/sky/CBspheres_refract.dae:8",
    "scenes/cs184/sky/CBspheres_microfacet_al_ag.dae:5",
    "scenes/cs184/sky/CBbunny_microfacet_cu.dae:5",
    "scenes/cs184/sky/CBgems.dae:8",
    "scenes/cs184/sky/CBcoil.dae:5",
    "scenes/cs184/keenan/banana.dae:3",
    "scenes/cornell.dae:5",
])


def cpu_model():
    """The CPU's name, with its family and model numbers on x86: some virtual
    machines name every Xeon generation alike ("Intel(R) Xeon(R) Processor")."""
    try:
        with open("/proc/cpuinfo") as f:
            first = f.read().split("\n\n")[0]
    except OSError:
        return "unknown CPU"
    fields = {}
    for line in first.splitlines():
        key, sep, value = line.partition(":")
        if sep:
            fields.setdefault(key.strip(), value.strip())
    name = fields.get("model name", "unknown CPU")
    if "cpu family" in fields and "model" in fields:
        return f"{name} (family {fields['cpu family']}, model {fields['model']})"
    return name


def reference_scenes():
    """(scene path, -m, reference file) of every image in the manifest."""
    with open(MANIFEST) as f:
        images = json.load(f)["images"]
    return [(os.path.join(i["scene_dir"], i["scene"]), i["max_ray_depth"], i["file"])
            for i in images]


def parse_specs(text, what):
    out = []
    for spec in filter(None, (s.strip() for s in text.split(","))):
        path, sep, m = spec.rpartition(":")
        if not sep or not m.isdigit():
            sys.exit(f"bench-mitsuba: {what} '{spec}': expected SCENE.dae:M (M = max ray depth)")
        out.append((path, int(m), None))
    return out


def ember_run(a, scene, m, out_dir):
    cmd = [a.ember, "-s", str(a.spp), "-m", str(m), "-r", str(a.r[0]), str(a.r[1]),
           "-f", os.path.join(out_dir, "ember.exr")] + a.ember_args.split() + [scene]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"bench-mitsuba: ember failed: {' '.join(cmd)}\n{p.stderr}")
    text = p.stderr + p.stdout
    rate = re.search(r"([0-9.]+) M samples/s", text)
    if not rate:
        sys.exit(f"bench-mitsuba: no 'M samples/s' in ember's output:\n{p.stderr}")
    how = re.search(r"; ([^;]+?) estimator, [^;]*threads, ([^;]+);", text)
    engine = f"{how.group(2)}, {how.group(1)}" if how else "? (summary line not understood)"
    return float(rate.group(1)) * 1e6, engine


def mitsuba_run(xml, variant, seed):
    cmd = [sys.executable, os.path.join(HERE, "mitsuba-render.py"), xml,
           "--variant", variant, "--renders", "2", "--seed", str(seed)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"bench-mitsuba: Mitsuba failed: {' '.join(cmd)}\n{p.stderr}")
    runs = [json.loads(line) for line in p.stdout.splitlines() if line.startswith("{")]
    return runs[-1]["samples_per_second"]


def particle_tracer_xml(xml):
    """The exported scene with Mitsuba's path tracer swapped for its particle tracer
    (the same max_depth, rr_depth and hide_emitters parameters)."""
    with open(xml) as f:
        text = f.read()
    if '<integrator type="path">' not in text:
        sys.exit(f"bench-mitsuba: {xml}: no path integrator to swap for ptracer")
    out = xml[:-len(".xml")] + "_ptracer.xml"
    with open(out, "w") as f:
        f.write(text.replace('<integrator type="path">', '<integrator type="ptracer">', 1))
    return out


def export(a, scene, m, tmp, name):
    folder = os.path.join(tmp, name)
    os.makedirs(folder, exist_ok=True)
    subprocess.run([a.ember, "export", "--format", "mitsuba", scene, "-r", str(a.r[0]),
                    str(a.r[1]), "-s", str(a.spp), "-m", str(m), "--sampler", a.sampler,
                    "--out", folder], check=True, stdout=subprocess.DEVNULL)
    return os.path.join(folder, os.path.splitext(os.path.basename(scene))[0] + ".xml")


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ember", required=True)
    p.add_argument("--rounds", type=int, help="interleaved rounds per scene (default 3; --quick: 1)")
    p.add_argument("--quick", action="store_true",
                   help="one round at 240x180, 16 spp: checks the whole set end to end in a few minutes")
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("-r", type=int, nargs=2, default=[480, 360])
    p.add_argument("--variants", default="llvm_ad_rgb", help="comma-separated, e.g. llvm_ad_rgb,scalar_rgb")
    p.add_argument("--sampler", default="independent",
                   help="Mitsuba's sampler (ember export --sampler); default independent, "
                        "Mitsuba's default and its cheapest per sample")
    p.add_argument("--no-references", action="store_true",
                   help="leave out the scenes of tests/data/references/manifest.json")
    p.add_argument("--extras", default=DEFAULT_EXTRAS,
                   help="extra scenes as SCENE.dae:M, comma-separated ('' for none); default: "
                        + DEFAULT_EXTRAS)
    p.add_argument("--ember-args", default="", help="extra ember flags, e.g. '--accel embree'")
    p.add_argument("--out", help="also write the rows as CSV here")
    a = p.parse_args()
    if a.quick:
        a.r, a.spp = [240, 180], 16
    a.rounds = a.rounds or (1 if a.quick else 3)
    if a.rounds < 1:
        sys.exit("bench-mitsuba: --rounds must be at least 1")
    os.chdir(ROOT)
    scenes = [] if a.no_references else reference_scenes()
    for path, m, ref in parse_specs(a.extras, "--extras"):
        if not any(s[0] == path and s[1] == m for s in scenes):
            scenes.append((path, m, ref))
    for path, _, _ in scenes:
        if not os.path.exists(path):
            sys.exit(f"bench-mitsuba: {path}: no such scene")
    rows = []
    start = time.time()
    with tempfile.TemporaryDirectory(prefix="ember-mitsuba-") as tmp:
        for path, m, ref in scenes:
            name = os.path.splitext(os.path.basename(path))[0]
            xml = export(a, path, m, tmp, f"{name}_m{m}")
            for variant in a.variants.split(","):
                ember, mitsuba, ptracer, engines, ptracer_xml = [], [], [], set(), None
                for i in range(a.rounds):
                    rate, engine = ember_run(a, path, m, tmp)
                    ember.append(rate)
                    engines.add(engine)
                    mitsuba.append(mitsuba_run(xml, variant, seed=2 * i))
                    line = (f"  {name} -m {m} {variant} round {i + 1}: ember {ember[-1] / 1e6:.2f}, "
                            f"Mitsuba {mitsuba[-1] / 1e6:.2f}")
                    if "light-tracing" in engine:
                        ptracer_xml = ptracer_xml or particle_tracer_xml(xml)
                        ptracer.append(mitsuba_run(ptracer_xml, variant, seed=2 * i))
                        line += f", Mitsuba ptracer {ptracer[-1] / 1e6:.2f}"
                    print(f"{line} M samples/s ({time.time() - start:.0f} s)", file=sys.stderr)
                engine = " / ".join(sorted(engines))
                for label, theirs in [(variant, mitsuba), (f"{variant} ptracer", ptracer)]:
                    if len(theirs) != len(ember):
                        continue
                    ratios = [e / mi for e, mi in zip(ember, theirs)]
                    rows.append((name, m, "yes" if ref else "no", engine, label,
                                 statistics.median(ember), statistics.median(theirs),
                                 statistics.median(ratios), min(ratios), max(ratios)))
    print(f"CPU: {cpu_model()}, {os.cpu_count()} threads; {a.r[0]}x{a.r[1]}, {a.spp} spp, each scene at its "
          f"reference's -m (extras at the -m given), {a.rounds} interleaved round(s), render-only medians; "
          f"Mitsuba 3.9.1 sampler {a.sampler}; ember flags: '{a.ember_args}'; {time.time() - start:.0f} s")
    print()
    print("| scene | -m | reference | ember ran | Mitsuba variant | ember M samples/s | Mitsuba M samples/s "
          "| ember/Mitsuba (median, min-max of pairs) |")
    print("|---|---:|---|---|---|---:|---:|---:|")
    for n, m, ref, eng, v, e, mi, r, lo, hi in rows:
        print(f"| {n} | {m} | {ref} | {eng} | {v} | {e / 1e6:.2f} | {mi / 1e6:.2f} | {r:.2f}x ({lo:.2f}-{hi:.2f}) |")
    if a.out:
        with open(a.out, "w") as f:
            f.write("scene,max_depth,reference,ember_engine,variant,ember_samples_per_s,"
                    "mitsuba_samples_per_s,ratio_median,ratio_min,ratio_max\n")
            for row in rows:
                f.write(",".join(f'"{x}"' if isinstance(x, str) and "," in x else str(x)
                                 for x in row) + "\n")


if __name__ == "__main__":
    main()

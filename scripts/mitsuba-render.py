#!/usr/bin/env python3
"""Renders a Mitsuba 3 scene exported by `ember export --format mitsuba` and
prints one JSON line per render: the render-only seconds, samples/s and the
image mean per channel, and the sample count the scene's sampler used (some
samplers round the requested count up). The first render of a process pays for JIT compilation
(llvm variants), so `--renders 2` times a second, warm call. Used by
scripts/bench-mitsuba and by the export tests; Mitsuba is never a dependency of
ember itself."""
import argparse
import json
import sys
import time


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("scene", help="exported .xml")
    p.add_argument("--variant", default="llvm_ad_rgb")
    p.add_argument("--spp", type=int, help="override the file's sample count")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--renders", type=int, default=1, help="renders in this process; each is reported")
    p.add_argument("--threads", type=int, default=0, help="0: all cores")
    p.add_argument("--out", help="write the last render here (EXR)")
    a = p.parse_args()

    import mitsuba as mi
    import numpy as np
    import drjit as dr
    mi.set_variant(a.variant)
    if a.threads > 0:
        mi.set_log_level(mi.LogLevel.Warn)
        dr.set_thread_count(a.threads)
    scene = mi.load_file(a.scene)
    sensor = scene.sensors()[0]
    spp = a.spp or sensor.sampler().sample_count()
    w, h = sensor.film().crop_size()
    img = None
    for i in range(a.renders):
        t0 = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=a.seed + i)
        dr.eval(img)
        dr.sync_thread()
        arr = np.asarray(img)  # forces the kernels to finish before the clock stops
        dt = time.perf_counter() - t0
        # The count the sampler took: some round the requested one up.
        spp = sensor.sampler().sample_count()
        mean = [float(arr[..., c].mean()) for c in range(3)]
        print(json.dumps({"render": i, "seconds": dt, "samples_per_second": w * h * spp / dt,
                          "width": int(w), "height": int(h), "spp": spp, "mean_rgb": mean,
                          "variant": a.variant, "seed": a.seed + i}), flush=True)
    if a.out:
        mi.util.write_bitmap(a.out, img)


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""A sizing pipeline in Python: sample 1,000 bodies, regenerate a garment on
every one, and print a table of fit figures with numpy.

With the MakeHuman data (../shared/data/makehuman, or $ATELIER_SHARED_DATA)
the bodies are MakeHuman adults and the garment is MakeHuman's
male_casualsuit01, fitted on the default body by its .mhclo binding and
encoded as a detail template. Without the data, the bodies are sampled
mannequins and the garment is the demo's shorts (cut from the reference
mannequin's skin, 8 mm out).

Run it after `make python` with Debian's interpreter (the module is built
against its NumPy):

    PYTHONPATH=build/python /usr/bin/python3 examples/pipeline.py [--bodies N] [--threads T]

or after `cmake --install build` with plain /usr/bin/python3. Ctrl-C stops
the regeneration (the engine is cancelled).
"""
import argparse
import os
import pathlib
import sys
import time

import numpy as np

import atelier


def progress(stage, done, total):
    print(f"\r  {stage}: {done}/{total}", end="", file=sys.stderr, flush=True)


def makehuman_job(data, n, seed):
    mh = atelier.MakeHuman(data / "makehuman")
    body = mh.reference()
    family = atelier.GarmentFamily(body)
    garment = atelier.encode_garment(family, mh.garment(data / "makehuman" / "clothes" / "male_casualsuit01.mhclo"),
                                     name="male_casualsuit01")
    bodies = mh.positions(mh.adults(n, seed)[0], dtype=np.float32)  # regen's adults (survey statures)
    return "MakeHuman adults", garment, bodies


def mannequin_job(n, seed):
    mannequin = atelier.Mannequin()
    body = mannequin.reference()
    family = atelier.GarmentFamily(body)

    def height(curve):
        return float(body.curve(curve)[:, 1].mean())

    y_knee, y_thigh, y_waist = height("knee_left"), height("thigh_left"), height("waist")
    shorts = atelier.skin_band_garment(body, 0.5 * (y_thigh + y_knee), y_waist + 0.02, 0.008, 0.40, "shorts")
    garment = atelier.encode_garment(family, shorts, name="shorts")
    bodies = mannequin.positions(atelier.sample_mannequins(n, seed), dtype=np.float32)
    return "sampled mannequins", garment, bodies


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--threads", type=int, default=0, help="0: all cores (results do not depend on it)")
    parser.add_argument("--data", type=pathlib.Path,
                        default=pathlib.Path(os.environ.get("ATELIER_SHARED_DATA", "../shared/data")))
    args = parser.parse_args()

    t0 = time.perf_counter()
    if (args.data / "makehuman" / "base.obj").exists():
        kind, garment, bodies = makehuman_job(args.data, args.bodies, args.seed)
    else:
        kind, garment, bodies = mannequin_job(args.bodies, args.seed)
    print(f"{len(bodies)} {kind} ({bodies.shape[1]} vertices each, {bodies.nbytes / 1e6:.0f} MB float32); "
          f"garment '{garment.name}': {garment.vertex_count} vertices, encoded in {time.perf_counter() - t0:.1f} s")

    t1 = time.perf_counter()
    result = atelier.regenerate(garment, bodies, threads=args.threads, progress=progress)
    seconds = time.perf_counter() - t1
    print(file=sys.stderr)
    positions, q = result.positions[0], result.quality[0]
    print(f"regenerated in {seconds:.1f} s ({1000 * seconds / len(bodies):.2f} ms per body); "
          f"positions {positions.shape} {positions.dtype}; {int(result.ok.sum())} bodies ok")

    # The table: each fit figure over the bodies that completed.
    ok = q[q["ok"]]
    columns = [
        ("inside vertices", ok["inside"].astype(float), 1, ""),
        ("pushed vertices", ok["pushed"].astype(float), 1, ""),
        ("min clearance", ok["min_clearance"], 1000, "mm"),
        ("mean clearance", ok["mean_clearance"], 1000, "mm"),
        ("clearance change", ok["clearance_change"], 1000, "mm"),
        ("clearance error", ok["clearance_error"], 1000, "mm"),
        ("strain p95", ok["strain_p95"], 100, "%"),
        ("strain max", ok["strain_max"], 100, "%"),
    ]
    print(f"\n{'fit figure':<18}{'unit':>5}{'min':>10}{'median':>10}{'p95':>10}{'max':>10}")
    for name, values, scale, unit in columns:
        lo, med, p95, hi = scale * np.percentile(values, [0, 50, 95, 100])
        print(f"{name:<18}{unit:>5}{lo:>10.3f}{med:>10.3f}{p95:>10.3f}{hi:>10.3f}")
    worst = np.argsort(q["strain_p95"])[::-1][:3]
    print("\nmost strained bodies: " + ", ".join(f"#{b} ({100 * q['strain_p95'][b]:.1f}%)" for b in worst))
    for b, error in enumerate(result.errors):
        if error:
            print(f"body {b} failed: {error}")
    return 0 if result.ok.all() else 1


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        sys.exit(130)

"""Benchmark of loading and saving big layouts: 5,000 / 10,000 / 20,000 widgets on four canvases.

Figures: ``load_s_N`` (``WorkspaceStore.load``: read, parse, check every value, build the model, look for
duplicate ids) and ``save_s_N`` (``WorkspaceStore.save``: check, write, fsync, rename), the best of
``--repeat`` runs each. Target: 20,000 widgets load in under 1 s (the store used to be quadratic in the
number of ids: 0.84 / 3.3 / 14.3 s).

Usage: ``python benchmarks/bench_layout.py [--sizes 5000 10000 20000] [--repeat 3] [--out FILE.json]``.
It measures the ``rcon_core`` it imports; for a before/after comparison run it once more with
``PYTHONPATH`` pointing at an older checkout.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

TARGETS = {"load_s_20000": 1.0}


def layout(widgets: int, canvases: int = 4) -> dict[str, Any]:
    """A layout like a real one, only bigger: sliders with a binding, a geometry and a few settings."""
    per = widgets // canvases
    return {"format": "rcon-workspace", "version": 1, "current": "c-0", "plugin_settings": {}, "canvases": [
        {"id": f"c-{c}", "name": f"Canvas {c}", "locked": c % 2 == 0, "widgets": [
            {"id": f"w-{c}-{i:06d}", "kind": "std.slider", "title": f"Speed {i}",
             "binding": {"name": f"/robot{i % 50}/speed", "type": "std_msgs/Float64", "role": "publish",
                         "field_paths": ["data"]},
             "geometry": {"x": float(i % 40 * 176), "y": float(i // 40 * 96), "w": 160.0, "h": 80.0},
             "settings": {"minimum": -1.5, "maximum": 2.0, "units": "m/s", "ticks": [0, 0.5, 1.0]}}
            for i in range(per)]}
        for c in range(canvases)]}


def best_of(repeat: int, fn: Any) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[5000, 10000, 20000])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", type=Path, default=None, help="also write the figures to this JSON file")
    args = parser.parse_args(argv)

    import rcon_core
    from rcon_core.canvas import WorkspaceStore

    print(f"rcon_core from {Path(rcon_core.__file__).parent}")
    figures: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sizes:
            path = Path(tmp) / f"layout-{n}.json"
            path.write_text(json.dumps(layout(n), indent=2))
            store = WorkspaceStore(path)
            ws = store.load()
            assert sum(len(c.widgets) for c in ws.canvases) == n // 4 * 4
            figures[f"load_s_{n}"] = round(best_of(args.repeat, store.load), 3)
            figures[f"save_s_{n}"] = round(best_of(args.repeat, lambda store=store, ws=ws: store.save(ws)), 3)
            size_mb = path.stat().st_size / 1e6
            print(f"{n:6d} widgets ({size_mb:5.1f} MB): load {figures[f'load_s_{n}']:6.3f} s   "
                  f"save {figures[f'save_s_{n}']:6.3f} s", flush=True)
    missed = [k for k, limit in TARGETS.items() if k in figures and figures[k] > limit]
    for key, limit in TARGETS.items():
        if key in figures:
            print(f"target {key} < {limit}: {'ok' if key not in missed else 'MISSED'} ({figures[key]})")
    if args.out is not None:
        args.out.write_text(json.dumps({"figures": figures, "targets": TARGETS}, indent=2) + "\n")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())

"""Work-precision charts and failure maps of the Rust integrators against scipy and numba baselines.

A thin wrapper of ``tribosweep bench`` (the bench wing, ``python/tribosweep/bench/``) that
also regenerates ``docs/benchmarks.md`` from the run:

    python benches/work_precision.py --quick             # about a minute on two cores
    python benches/work_precision.py --out bench_out     # full ladder rtol 1e-3..1e-12
    python benches/work_precision.py --from-json bench_out/work_precision.json   # docs only, no measuring

Every other option is ``tribosweep bench``'s (``--scene``, ``--rtol``, ``--n``, ``--skip``, ...). Nothing
here asserts a time; the ratios are measured in one process on the same machine.
"""

from __future__ import annotations

import os
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent
DOCS = HERE.parent / "docs" / "benchmarks.md"


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if "--from-json" in argv:
        from tribosweep.bench.workprecision import load_payload, render_docs

        i = argv.index("--from-json")
        payload = load_payload(argv[i + 1])
        out = pathlib.Path(argv[argv.index("--docs") + 1]) if "--docs" in argv else DOCS
        out.write_text(render_docs(payload, command=payload.get("command"),
                                   extra=payload.get("failure_maps_markdown", "")))
        print(f"docs: {out}")
        return 0
    from tribosweep import cli

    if "--no-docs" in argv:
        argv.remove("--no-docs")
    elif "--docs" not in argv:
        rel = os.path.relpath(DOCS)
        argv += ["--docs", rel if not rel.startswith("..") else str(DOCS)]
    return cli.main(["bench", *argv])


if __name__ == "__main__":
    raise SystemExit(main())

"""Benchmark 12 on a GPU: ``python bench/gpu_batch.py`` runs bench/worlds.py on ``cuda`` with 1, 64, 1,024 and
8,192 worlds (``--device cuda:N``, ``--worlds``, ``--steps``, ``--out FILE``: see ``--help``).

Needs the mujoco_warp extra and a CUDA device Warp sees; the first run compiles Warp's CUDA kernels (minutes),
later runs load them from Warp's kernel cache. Copy the printed table into bench/results.md, section 12.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.worlds import GPU_SIZES, main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:], device="cuda", sizes=GPU_SIZES))

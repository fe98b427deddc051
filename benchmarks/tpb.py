"""``python -m benchmarks.tpb ...`` = ``python -m benchmarks.run --study three_point_bending ...``.

    python -m benchmarks.tpb --resolution paper --scheme monolithic
    python -m benchmarks.tpb --resolution quick --scheme single-pass monolithic --reference
"""
import sys

from .run import main

if __name__ == "__main__":
    sys.exit(main(study="three_point_bending", prog="benchmarks.tpb"))

"""The C test programs of the "Function" check and how to build them."""

from pathlib import Path

from robosoc.firmware import MATRIX_BENCH_SOURCE

PROGRAMS_DIR = Path(__file__).resolve().parent

#: name -> (sources, preprocessor defines, expected exit code)
PROGRAMS: dict[str, tuple[list[Path], dict[str, str | int | None], int]] = {
    "int32_arith": ([PROGRAMS_DIR / "int32_arith.c"], {}, 0),
    "int64_arith": ([PROGRAMS_DIR / "int64_arith.c"], {}, 0),
    "softfloat": ([PROGRAMS_DIR / "softfloat.c"], {}, 0),
    "fixed_q16": ([PROGRAMS_DIR / "fixed_q16.c"], {}, 0),
    "crc_sort_string": ([PROGRAMS_DIR / "crc_sort_string.c"], {}, 7),
    "matrix7": ([MATRIX_BENCH_SOURCE], {"BENCH_ITERATIONS": 2}, 0),
}

"""The C preprocessor subset of Marlin's headers (:mod:`wavecheck.firmware.preprocessor`): C's
integer arithmetic, Marlin's ENABLED()/TERN(), macros that name macros, and branches the files
cannot decide kept as candidates, never picked silently."""

from __future__ import annotations

from fractions import Fraction

import pytest

from wavecheck.firmware.preprocessor import Headers, Num, evaluate

HEADER = """
#define ON
#define ONE 1
#define TWO 2
#define ALIAS ONE
#define BOARD BOARD_RAMPS_14_EFB
#define DRV A4988
//#define OFF
/* #define HIDDEN
*/
#define LONG 1 + \\
  2
"""


@pytest.mark.parametrize(
    ("expr", "value"),
    [
        ("4000/3", Num(Fraction(1333), True)),  # C integer division truncates
        ("-7/2", Num(Fraction(-3), True)),  # toward zero
        ("-7%2", Num(Fraction(-1), True)),  # the remainder takes the dividend's sign
        ("78.7402*2", Num(Fraction("157.4804"), False)),
        ("200 * 16 / double(2) / double(20)", Num(Fraction(80), False)),
        ("ALIAS + TWO", Num(Fraction(3), True)),  # a macro that names a macro
        ("LONG", Num(Fraction(3), True)),  # a continued line
        ("ENABLED(ON) && DISABLED(OFF)", Num(Fraction(1), True)),
        ("ENABLED(TWO)", Num(Fraction(0), True)),  # Marlin: only empty, 1, 0x1, true
        ("ANY(OFF, ON)", Num(Fraction(1), True)),
        ("defined(HIDDEN) || defined OFF", Num(Fraction(0), True)),  # comments hide defines
        ("BOARD == BOARD_RAMPS_14_EFB", Num(Fraction(1), True)),
        ("BOARD == BOARD_BTT_SKR_V1_4", Num(Fraction(0), True)),  # board names are distinct
        ("TERN(ON, 5, 6) + TERN0(OFF, 9)", Num(Fraction(5), True)),
        ("1 ? TWO : ONE", Num(Fraction(2), True)),
        ("DRV", "A4988"),
        ("HAS_SOMETHING", "HAS_SOMETHING"),  # not defined here: a symbol, not 0
        ("HAS_SOMETHING > 1", None),  # undecidable
        ("1 << 100000", None),  # bounded
        ("(" * 3000 + "1" + ")" * 3000, None),  # bounded
        ("1e99999", None),
    ],
)
def test_expressions(expr: str, value: object) -> None:
    h = Headers()
    h.feed("t.h", HEADER)
    assert evaluate(h, expr) == value


def test_branches_decided_and_undecided() -> None:
    h = Headers()
    h.feed("c.h", HEADER + """
#if ENABLED(ON)
  #define A 1
#else
  #define A 2
#endif
#if HAS_SOMETHING
  #define B TMC2209
#elif ENABLED(OFF)
  #define B DRV8825
#else
  #define B A4988
#endif
#define C 1
#if HAS_OTHER
  #define C 2
#endif
""")  # fmt: skip
    assert [d.value for d in h.candidates("A")] == ["1"]
    b = h.candidates("B")  # every arm defines B: the earlier "not defined" is gone
    assert [d.value for d in b] == ["TMC2209", "A4988"]  # the DRV8825 arm is certainly false
    assert b[0].depends == ("#if HAS_SOMETHING at c.h:19",)
    assert [d.value for d in h.candidates("C")] == ["1", "2"] and h.definition("C") is None

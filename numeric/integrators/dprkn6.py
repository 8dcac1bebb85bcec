"""Dormand–Prince RKN 6(4): an embedded Runge–Kutta–Nyström pair of orders 6 and 4, 6 stages,
first same as last (5 force evaluations per step). Its nodes involve ``√8581``; the entries are
stored exactly as ``p + q·√8581``.

J. R. Dormand and P. J. Prince, "Runge–Kutta–Nyström triples", Comput. Math. Appl. 13 (1987)
937–949 (RKN6(4)6FD; the same numbers as DifferentialEquations.jl's ``DPRKN6``).
"""

from __future__ import annotations

from fractions import Fraction

from .nystrom import EmbeddedNystrom
from .nystrom_tables import NystromTable, Surd, q


def _r(p: str, s: str = "0") -> Surd:
    """``p + s·√8581`` with rational ``p`` and ``s``."""
    return Surd(Fraction(p), Fraction(s), 8581)


_a63 = _r("84119543/409622616", "366727/409622616")
_a64 = _r("84119543/409622616", "-366727/409622616")
_bp3 = _r("389225579/1024056540", "96856/1024056540")
_bp4 = _r("389225579/1024056540", "-96856/1024056540")
_b = (q("329/4212"), 0, _a63, _a64, q("200/17901"), 0)

DPRKN6_TABLE = NystromTable(
    name="dprkn6",
    c=(0, _r("209/900", "-1/900"), _r("209/450", "-1/450"), _r("209/450", "1/450"), q("9/10"), 1),
    a=(
        (),
        (_r("26131/810000", "-209/810000"),),
        (_r("26131/607500", "-209/607500"), _r("26131/303750", "-209/303750")),
        (_r("980403512254/11694469921875", "7781688431/11694469921875"),
         _r("-1262884486208/11694469921875", "-15385481287/11694469921875"),
         _r("7166233891441/46777879687500", "78694563299/46777879687500")),
        (_r(str(Fraction(-9 * 329260, 27040000)), str(Fraction(-9 * 3181, 27040000))),
         _r(str(Fraction(27 * 35129, 13520000)), str(Fraction(27 * 3331, 13520000))),
         _r(str(Fraction(-27 * 554358343, 464060480000)), str(Fraction(-27 * 31040327, 464060480000))),
         _r(str(Fraction(153 * 8555257, 2745920000)), str(Fraction(-153 * 67973, 2745920000)))),
        _b[:5],
    ),
    b=_b,
    bp=(q("329/4212"), 0, _bp3, _bp4, q("2000/17901"), q("1/20")),
    # embedded weights b̂ = b − b̃ from the published differences b̃
    b_hat=(_r("2701/4563", "23/4563"), _r("-9829/9126", "-131/9126"), _r(str(Fraction(5 * 1798, 9126)),
                                                                          str(Fraction(5 * 17, 9126))), 0, 0, 0),
    bp_hat=(q("115/2106"), 0, _r("84119543/256014135", "366727/256014135"),
            _r("84119543/256014135", "-366727/256014135"), q("6950/17901"), q("-1/10")),
    order=6,
    embedded_order=4,
    fsal=True,
    source="Dormand & Prince, Comput. Math. Appl. 13 (1987) 937-949, RKN6(4)6FD",
)


#: Dormand–Prince RKN 6(4) as an adaptive method (its name, and the table that declares its order).
DPRKN6 = EmbeddedNystrom.of("dprkn6", DPRKN6_TABLE)

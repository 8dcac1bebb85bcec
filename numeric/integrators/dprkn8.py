"""Dormand–Prince RKN 8(6): an embedded Runge–Kutta–Nyström pair of orders 8 and 6, 9 stages,
first same as last (8 force evaluations per step).

J. R. Dormand and P. J. Prince, "Runge–Kutta–Nyström triples", Comput. Math. Appl. 13 (1987)
937–949 (the 8(6) pair; the same numbers as DifferentialEquations.jl's ``DPRKN8``).
"""

from __future__ import annotations

from .nystrom import EmbeddedNystrom
from .nystrom_tables import NystromTable, q

_c = ("0", "1/20", "1/10", "3/10", "1/2", "7/10", "9/10", "1", "1")
_b = ("223/7938", "0", "1175/8064", "925/6048", "41/448", "925/14112", "1175/72576", "0", "0")

DPRKN8_TABLE = NystromTable(
    name="dprkn8",
    c=tuple(q(v) for v in _c),
    a=tuple(tuple(q(v) for v in row) for row in (
        (),
        ("1/800",),
        ("1/600", "1/300"),
        ("9/200", "-9/100", "9/100"),
        ("-66701/197352", "28325/32892", "-2665/5482", "2170/24669"),
        ("227015747/304251000", "-54897451/30425100", "12942349/10141700", "-9499/304251", "539/9250"),
        ("-1131891597/901789000", "41964921/12882700", "-6663147/3220675", "270954/644135", "-108/5875",
         "114/1645"),
        ("13836959/3667458", "-17731450/1833729", "1063919505/156478208", "-33213845/39119552",
         "13335/28544", "-705/14272", "1645/57088"),
        _b[:8],
    )),
    b=tuple(q(v) for v in _b),
    bp=tuple(q(v) for v in ("223/7938", "0", "5875/36288", "4625/21168", "41/224", "4625/21168", "5875/36288",
                            "223/7938", "0")),
    b_hat=tuple(q(v) for v in ("7987313/109941300", "0", "1610737/44674560", "10023263/33505920",
                               "-497221/12409600", "10023263/78180480", "1610737/402071040", "0", "0")),
    bp_hat=tuple(q(v) for v in ("7987313/109941300", "0", "1610737/40207104", "10023263/23454144",
                                "-497221/6204800", "10023263/23454144", "1610737/40207104",
                                "-4251941/54970650", "3/20")),
    order=8,
    embedded_order=6,
    fsal=True,
    source="Dormand & Prince, Comput. Math. Appl. 13 (1987) 937-949, RKN8(6)",
)


#: Dormand–Prince RKN 8(6) as an adaptive method (its name, and the table that declares its order).
DPRKN8 = EmbeddedNystrom.of("dprkn8", DPRKN8_TABLE)

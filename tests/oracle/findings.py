"""Every failure the oracle found, as a minimal scene: issue 31's listed findings and the new ones.

Each :class:`Case` is a scene (TOML text and tables) and the outputs to check; ``test_oracle.py`` runs
:func:`oracle.checks.check_scene` (or a spectrum check) on it and expects no finding. Cases still failing
carry ``xfail`` (strict): when the fix lands the test passes, pytest reports XPASS as a failure, and the
mark is removed. ``known`` is issue 31's finding, or ``None`` for a finding this oracle found (``new``
says what it is).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .scenes import GeneratedRecord


@dataclass(frozen=True)
class Case:
    id: str
    text: str = ""
    tables: dict = field(default_factory=dict)
    outputs: tuple = ("modes",)
    frf_pair: tuple | None = None
    record: GeneratedRecord | None = None
    features: frozenset = frozenset()
    cli: tuple = ()  # command-line arguments ("{scene}" is the scene's path): checked for exit 0 or one line
    timeout: float = 300.0  # seconds the command may take
    known: str | None = None  # issue 31's wording
    new: str | None = None  # what this oracle found (not in issue 31)
    failing: bool = True


def scene(name: str, params: dict, body: str) -> str:
    p = "\n".join(f"{k} = {v!r}" for k, v in params.items())
    return f'name = "{name}"\n\n[parameters]\n{p}\n\n{body.strip()}\n'


#: Four unevenly spaced rows, the last one nonzero: the oscillator's largest |u| comes after the record.
PULSE = GeneratedRecord((0.0, 0.13, 0.31, 0.4), (0.0, 1.0, -0.4, 0.7), (0.0, 0.05), (1.0, 5.0))
#: Evenly spaced rows ending at 0: a record the product's spectrum gets right (to keep other cases apart).
EVEN = GeneratedRecord((0.0, 0.1, 0.2, 0.3, 0.4), (0.0, 1.0, -0.4, 0.7, 0.0), (0.05,), (1.0,))

CASES = [
    # -- issue 31's findings (being fixed) ----------------------------------------------------------------
    Case("spectrum_free_vibration_after_record", failing=False, record=PULSE, outputs=("spectrum",),
         known="response spectra miss the peak after the record ends"),
    Case("spectrum_time_long_period", failing=False, record=GeneratedRecord((0.0, 0.02, 0.04), (0.5, -0.1, 0.0), (0.05,), (1e9,)),
         outputs=("spectrum_time",),
         known="response spectra: time grows as period/step (T = 1e9 s on a 0.02 s record: no answer in 15 s; "
               "T = 1e7 s takes 7 s; found as an rsa that did not finish in 300 s on a generated scene whose "
               "slowest mode has T = 1.4e9 s)"),
    Case("rsa_record_free_vibration", scene("sdof_rsa", {"m": 1.0, "k": 1.5791367041742972}, '''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
k = "k"
[damping]
modal = 0.05
'''), outputs=("rsa",), record=PULSE, known="response spectra miss the peak after the record ends (rsa, T = 5 s)", failing=False),
    Case("wall_spring_1e-90", scene("weak_wall", {"m": 1.0, "k": 1.0, "kw": 1e-90}, '''
[masses]
p = "m"
q = "m"
[[springs]]
between = ["wall", "p"]
k = "kw"
[[springs]]
between = ["p", "q"]
k = "k"
'''), known="contrast: a wall spring 1e-90 of its neighbour prints omega^2 = 0.0", failing=False),
    Case("weak_link_2e-70", scene("weak_link", {"m": 1.0}, '''
[masses]
p = "m"
q = "m"
[[springs]]
between = ["wall", "p"]
k = "1"
[[springs]]
between = ["p", "q"]
k = "2e-70"
'''), known="contrast: omega^2 = 0.0 printed for the elastic mode of a 2e-70 link (true 1e-70)", failing=False),
    Case("frf_contrast_1e36", scene("frf36", {"m": 1.0, "k": 1.0, "K": 1e36}, '''
[masses]
p = "m"
q = "m"
[[springs]]
between = ["wall", "p"]
k = "k"
[[springs]]
between = ["p", "q"]
k = "K"
'''), outputs=("frf",), frf_pair=(0, 1), known="contrast: frf 'matrix is numerically singular' from 1e36", failing=False),
    Case("lennard_jones_under_gravity", scene("lj", {"m": 0.3, "eps": 0.05, "r0": 1.12, "g": 0.1}, '''
[masses]
a = "m"
b = "m"
[[springs]]
between = ["wall", "a"]
potential = "eps*((r0/(r0 + d))**12 - 2*(r0/(r0 + d))**6)"
[[springs]]
between = ["a", "b"]
potential = "eps*((r0/(r0 + d))**12 - 2*(r0/(r0 + d))**6)"
[gravity]
g = "g"
'''), features=frozenset({"potential:lennard_jones"}),
         known="Lennard-Jones springs under any constant load are refused", failing=False),
    Case("spring_forces_hanging_contrast", scene("hang6", {"m": 1.0, "g": -9.81}, '''
[masses]
a = "m"
b = "m"
c = "m"
d1 = "m"
e = "m"
f = "m"
[[springs]]
between = ["wall", "a"]
k = "1e-6"
[[springs]]
between = ["a", "b"]
k = "1.5848931924611134e-4"
[[springs]]
between = ["b", "c"]
k = "0.025118864315095794"
[[springs]]
between = ["c", "d1"]
k = "3.981071705534973"
[[springs]]
between = ["d1", "e"]
k = "630.957344480193"
[[springs]]
between = ["e", "f"]
k = "1e6"
[gravity]
g = "g"
[simulation]
dt = 1.0
steps = 100
'''), outputs=("simulate",), features=frozenset({"regime:wide"}),
         known="time-history spring forces at contrast (simulate --springs, hanging chain 1e-6 ... 1e6)", failing=False),
    Case("frf_infinite_at_a_near_node", scene("frf36d", {"m": 1.0, "k": 1.0, "K": 1e36, "c": 0.1}, '''
[masses]
p = "m"
q = "m"
[[springs]]
between = ["wall", "p"]
k = "K"
[[springs]]
between = ["p", "q"]
k = "k"
[[dampers]]
between = ["q", "wall"]
c = "c"
'''), outputs=("frf",), frf_pair=(1, 1),
         known="frf resonance table: '|H| = inf' at omega_n = 1e18, a mode whose coupling to the output is 1e-72 "
               "(|H| there is 1.0 to 17 digits)", failing=False),
    Case("frf_unconnected_pieces", scene("apart", {"m": 0.026, "M": 5.0, "Q": 0.35, "k": 0.41}, '''
[masses]
a = "m"
b = "M"
c = "Q"
[[springs]]
between = ["b", "c"]
k = "k"
[damping]
modal = 0.018
'''), outputs=("frf",), frf_pair=(0, 1), known="frf resonance table: resonances listed for H = 0 (unconnected)", failing=False),
    Case("frf_peak_not_a_local_maximum", scene("farpeak", {
        "m": 1408.997650436614, "w": 98898345.09000109, "c2": 1.0, "k": 2.165255687336383e-11,
        "x": 170871782964.03098, "h": 15.811388300841896}, '''
[masses]
m1 = "m"
base = "w"
atom = "c2"
[[springs]]
between = ["m1", "base"]
k = "sqrt(k)"
[[springs]]
between = ["base", "atom"]
k = "2*x"
[[springs]]
between = ["wall", "base"]
k = "3*h"
[[springs]]
between = ["wall", "m1"]
k = "x/2"
[damping]
modal = 0.002550157606663858
'''), outputs=("frf",), frf_pair=(2, 0),
         known="frf resonance table: an 'exact peak' (omega = 584561.61) that is not a local maximum of |H| "
               "(|H| rises through it); found by the generator", failing=False),
    Case("prestressed_without_initial", scene("pre", {"m": 1.0, "k": 1.0, "T0": 0.5}, '''
[masses]
p = "m"
q = "m"
[[springs]]
between = ["wall", "p"]
potential = "T0*d + k*d**2/2"
[[springs]]
between = ["p", "q"]
k = "k"
'''), outputs=("simulate",), known="a pre-stressed potential scene without [initial] is told its motion is zero", failing=False),
    Case("damped_chain_frf_zeta_not_computed", scene("dchain", {"m": 0.25, "k": 3.0, "c": 0.05}, '''
[chain]
n = 4
mass = "m"
k = "k*(1 + i % 2)"
left = "wall"
right = "free"
[[dampers]]
between = [0, "wall"]
c = "c"
'''), outputs=("frf",), frf_pair=(0, 3), features=frozenset({"form:chain"}),
         known="smaller: damped [chain] frf prints 'zeta not computed' while modes computes it", failing=False),
    Case("rsa_potential_note_about_zero", scene("rsapot", {"m": 1.0, "k": 2.0, "beta": 0.5, "g": -1.0}, '''
[masses]
p = "m"
q = "m"
[[springs]]
between = ["wall", "p"]
potential = "k*d**2/2 + beta*d**4/4"
[[springs]]
between = ["p", "q"]
k = "k"
[damping]
modal = 0.05
[gravity]
g = "g"
'''), outputs=("rsa",), record=EVEN,
         known="smaller: rsa on a potential scene says 'linearization about x = 0' (its numbers are about x_eq)", failing=False),
    Case("cli_frf_contrast_1e36", scene("frf36", {"m": 1.0, "k": 1.0, "K": 1e36}, '''
[masses]
p = "m"
q = "m"
[[springs]]
between = ["wall", "p"]
k = "k"
[[springs]]
between = ["p", "q"]
k = "K"
'''), outputs=("cli",), cli=("frf", "{scene}", "--input", "p", "--output", "q", "--json"),
         known="contrast: 'springchain frf' at contrast 1e36 ends in a traceback (exit 1) instead of one line", failing=False),
    # -- found by this oracle (not in issue 31) ------------------------------------------------------------
    Case("N1_equilibrium_json_damped", scene("eqjson", {"m": 1.0, "k": 2.0, "beta": 0.5, "g": -1.0, "c": 0.1}, '''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
potential = "k*d**2/2 + beta*d**4/4"
[[dampers]]
between = ["p", "wall"]
c = "c"
[gravity]
g = "g"
'''), new="modes --json of a damped potential scene has no 'equilibrium' (README: --json adds it; "
          "derive/report.py modes_json overwrites `extra` with the damping fields)", failing=False),
    Case("N2_cubic_under_gravity", scene("cubic_sag", {"m": 1.0, "k": 2.0, "kappa": 0.5, "g": -1.0}, '''
[masses]
p = "m"
q = "m"
[[springs]]
between = ["wall", "p"]
k = "k"
k3 = "kappa"
[[springs]]
between = ["p", "q"]
k = "k"
[gravity]
g = "g"
'''), features=frozenset({"spring:cubic", "gravity"}),
         new="a cubic (k3) spring under gravity or a constant force: modes prints 'x_eq = K^-1 M g' = (-1, -1.5) "
             "and the modes of the linear springs, ignoring k3: omega^2 = 0.7639, 5.2361 printed; about the true "
             "equilibrium (-0.8477, -1.3477) they are 1.0154, 6.0625", failing=False),
    Case("N3_potential_simulate_springs", scene("pot_springs", {"m": 1.0, "k": 1.0, "beta": 0.5}, '''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
potential = "k*d**2/2 + beta*d**4/4"
[initial]
x = [0.5]
[simulation]
dt = 0.01
steps = 10
'''), outputs=("simulate",),
         new="simulate(springs=True) / --springs on a scene with a potential spring: AttributeError "
             "'cubic_constants' (numeric/storeys.py spring_series)", failing=False),
    Case("N3_cli_simulate_springs", scene("pot_springs", {"m": 1.0, "k": 1.0, "beta": 0.5}, '''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
potential = "k*d**2/2 + beta*d**4/4"
[initial]
x = [0.5]
[simulation]
dt = 0.01
steps = 10
'''), outputs=("cli",), cli=("simulate", "{scene}", "--springs", "--no-figures"),
         new="'springchain simulate --springs' on a potential scene: a traceback (AttributeError cubic_constants)", failing=False),
    Case("N3_chain_k3_simulate_springs", scene("chain_k3", {"m": 1.0, "k": 1.0, "kappa": 0.5}, '''
[chain]
n = 3
mass = "m"
k = "k"
k3 = "kappa"
left = "wall"
right = "free"
[initial]
x = [0.1, 0.0, 0.0]
[simulation]
dt = 0.01
steps = 10
'''), outputs=("simulate",), features=frozenset({"form:chain", "spring:cubic"}),
         new="simulate(springs=True) on a [chain] with k3: AttributeError 'cubic_constants'", failing=False),
    Case("N4_potential_tension", scene("pot_k3", {"m": 1.0, "k": 1.0, "w": 2.0, "kappa": 1.0}, '''
[masses]
p = "m"
q = "m"
[[springs]]
between = ["wall", "p"]
potential = "k*(exp(w*d) - 1 - w*d)/w**2"
[[springs]]
between = ["p", "q"]
k = "k"
k3 = "kappa"
[initial]
x = [0.5, 0.0]
[simulation]
dt = 0.01
steps = 10
'''), outputs=("simulate",), features=frozenset({"potential:exp", "spring:cubic"}),
         new="simulate(springs=True) with a potential spring beside a k3 spring: the potential spring's "
             "'tension' is V''(0)*d, not V'(d) (here k*d instead of k*(exp(w d) - 1)/w: 0.5 vs 0.859)", failing=False),
    Case("N5_last_frame_with_table", scene("last_frame", {"m": 1.0, "k": 1.0}, '''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
k = "k"
[[forces]]
on = "p"
table = "f.csv"
[initial]
x = [1.0]
[simulation]
dt = 0.1
steps = 16
record_every = 3
'''), tables={"f.csv": "t,f\n0,0\n1,1\n2,0\n"}, outputs=("simulate",), features=frozenset({"force:table"}),
         new="exact method with a table load and steps not a multiple of record_every: the last recorded "
             "frame (t = 1.6) is the initial state x = 1.0 (true 0.500512; verlet 0.500440 beside it); drifts, "
             "spring forces and base shear of that frame with it", failing=False),
    Case("N6_overdamped_chain_warning", scene("od_chain", {"m": 1.75e-116, "k": 9e-118, "c": 7e128}, '''
[chain]
n = 3
mass = "m"
k = "k"
left = "wall"
right = "free"
[[dampers]]
between = ["i", "i+1"]
c = "c"
'''), features=frozenset({"form:chain"}),
         new="modes of a strongly overdamped [chain] leak 'ComplexWarning: Casting complex values to real' "
             "(numeric/linear_exact.py:144) on stderr", failing=False),
    Case("N7_frf_low_resonance_wide_contrast", scene("trial", {
        "energy": 7.0, "omega": 47227097.37989884, "m": 56855207.99507734, "beta": 0.003153239924458225, "k": 1.0,
        "M": 196671362653.1338, "K": 1.3191229012370379e-05, "alpha": 3.0, "E": 1.5, "np": 1.0,
        "Omega": 0.03869820547103473}, '''
[masses]
top = "energy"
cart = "3*omega"
q = "m"
m3 = "beta"
s = "k"
[[springs]]
between = ["top", "cart"]
k = "M"
[[springs]]
between = ["cart", "q"]
k = "K"
[[springs]]
between = ["q", "m3"]
k = "omega/2"
[[springs]]
between = ["m3", "s"]
k = "sqrt(alpha)"
[[springs]]
between = ["s", "top"]
potential = "-E*np**2*log(1 - (d/np)**2)/2"
[[springs]]
between = ["wall", "m3"]
k = "Omega"
[[dampers]]
between = ["cart", "m3"]
c = "M"
'''), outputs=("frf",), frf_pair=(2, 2), features=frozenset({"regime:wide"}),
         new="frf H off by 4.3e-9 and the 'exact peak' |H| by 2.5e-9 relative (README: <= 1e-10) at the lowest resonance "
             "(omega = 1.396e-5 rad/s) of a generated 5-mass loop (stiffness 1.3e-5 ... 2e11, a 2e11 dashpot); "
             "found by the generator (also: '|H| = inf' claimed at omega_n = 1.798 where |H| is 2.8e-10). The value is exact "
             "for the elements as float64 rounds '3*omega': H moves by 1.4e-4 relative under a last-bit change of the "
             "elements there, which a note now states", failing=False),
    Case("N9_rayleigh_prestressed_not_proportional", scene("ray7", {"m": 1.0, "k": 4.0, "T": 0.01}, '''
[masses]
a = "m"
p = "m"
q = "m"
[[springs]]
between = ["wall", "a"]
k = "k"
[[springs]]
between = ["a", "p"]
potential = "T*d + k*d**2/2"
[damping]
rayleigh = ["0.1", "0.01"]
'''), features=frozenset({"potential:prestressed", "damping:rayleigh"}),
         new="Rayleigh damping (C = alpha M + beta K, proportional by construction) on a scene whose pre-stressed "
             "potential moves x_eq: modes --json says 'proportional': false and lists complex_modes (the zeta "
             "values themselves are right)", failing=False),
    Case("N10_chain_potential_constant_part", scene("chpot", {"m": 1.0, "k": 1.0, "beta": 0.5}, '''
[chain]
n = 3
mass = "m"
potential = "k*d**2/2 + beta*d**4/4"
left = "wall"
right = "free"
[[forces]]
on = 2
f = "0.5 + 0.5*sin(2*t)"
'''), features=frozenset({"form:chain", "potential:fput_beta", "force:harmonic2"}),
         new="a [chain] with a potential and a force with a constant part ('0.5 + 0.5*sin(2*t)'): not refused "
             "(f = '0.5' and gravity are, in one line: 'not supported yet for [chain] scenes'); modes prints the "
             "modes about x = 0 (omega^2 0.198, 1.555, 3.247; about the equilibrium 0.259, 2.034, ...)", failing=False),
    Case("N11_ground_constant_potential_equilibrium", scene("gpot", {"m": 1.0, "k": 2.0, "beta": 0.5, "A": -1.0}, '''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
potential = "k*d**2/2 + beta*d**4/4"
[ground]
acceleration = "A"
'''), features=frozenset({"potential:fput_beta", "ground:const"}),
         new="a potential scene under a constant ground acceleration (README: a static load, like gravity): the "
             "equilibrium ignores it (extension 0.0; true 0.47347, from k d + beta d^3 = -m A) and omega^2 = 2.0 "
             "is printed (true 2.33625)", failing=False),
    Case("N12_gamma_on_wrong_modes", scene("gam", {"r0": 4.842407363348041e+85, "m": 8.874252669080051e-100,
                                                    "x": 8.49967488917427e-39, "K": 2.4863551500489254e+48,
                                                    "k": 1.338275454088706e-56, "Omega": 3.239742272314865e+89}, '''
[masses]
s = "sqrt(r0)"
floor3 = "r0"
m1 = "m/3"
z1 = "x"
[[springs]]
between = ["s", "floor3"]
k = "3*r0"
[[springs]]
between = ["floor3", "m1"]
k = "K"
[[springs]]
between = ["floor3", "z1"]
k = "k"
[[springs]]
between = ["s", "wall"]
k = "Omega"
'''), features=frozenset({"regime:extreme"}),
         new="at extreme contrast (masses 3e-100 ... 5e85, omega^2 1.6e-18 ... 8e147) omega^2 is printed right but "
             "the participation factors belong to other modes: Gamma = 6.96e42, 3.8e-17, -1.1e-100, ... printed for "
             "modes whose Gamma is 9.2e-20, 6.96e42, 2.64e21 (found by the generator)", failing=False),
    Case("N13_modes_hang_damping_closed_form", scene("h6", {
        "B": 6.993932514095252e+127, "c": 1.5178166621250607e-31, "m": 5.385133973702211e+41,
        "E": 3.433181247333999e-30, "nu": 1.1402926230363904e-86, "k": 6.202436704823775e-78}, '''
[masses]
left = "m"
u = "4*E"
bob = "3*B"
[[springs]]
between = ["left", "u"]
k = "nu"
[[springs]]
between = ["wall", "left"]
k = "k/3"
[[dampers]]
between = ["left", "wall"]
c = "4*E"
[[dampers]]
between = ["bob", "u"]
c = "1.5*c"
'''), outputs=("cli",), cli=("modes", "{scene}", "--json"), timeout=20.0,
         new="'springchain modes' hangs (> 100 s; stack: sympy cancel in derive/damping_report.py _closed_forms) on "
             "3 masses and 2 dashpots with values from 1e-86 to 1e128 (the same topology with moderate values: 3 s); "
             "the symbolic caps count operations, not the size of the exact rationals. Found by the generator", failing=False),
    Case("N14_modes_hang_rayleigh_targets", scene("v3", {
        "K": 4.809548920040937, "m": 0.040160135993826354, "k": 13.948993900564439, "E": 0.3578227611390599,
        "F0": 18.974974538670008}, '''
[masses]
atom = "K"
q = "0.5*K"
floor2 = "m*K"
[[springs]]
between = ["wall", "atom"]
k = "k*K"
[[springs]]
between = ["q", "floor2"]
k = "F0"
[[springs]]
between = ["wall", "floor2"]
k = "sqrt(k)"
[[springs]]
between = ["floor2", "wall"]
k = "0.5*E"
[damping]
rayleigh_targets = {zeta = [0.05, 0.05], modes = [1, 2]}
'''), outputs=("cli",), cli=("modes", "{scene}", "--json"), timeout=20.0,
         new="'springchain modes --json' hangs (> 80 s; stack: sympy radsimp in derive/rayleigh_targets.py "
             "closed_form) on three masses with linear springs, Rayleigh damping from targets and parameters that "
             "are generic floats (the same scene with round values: 3 s). Found by the generator", failing=False),
    Case("N15_overdamped_chain_zeta", scene("odc", {"m": 1.0, "k": 1.0, "c": 3.0}, '''
[chain]
n = 3
mass = "m"
k = "k"
left = "free"
right = "free"
[[dampers]]
between = ["i", "wall"]
c = "c"
'''), features=frozenset({"form:chain"}),
         new="a [chain] of 3 equal masses with a dashpot c = 3 from every mass to the ground (C = 3 M: proportional, "
             "zeta_j = c/(2 m omega_j)): modes --json gives zeta = 1.5797 for the mode omega^2 = 1, whose zeta is "
             "1.5 exactly (the other elastic mode's 0.866 is right). Found by the generator", failing=False),
    Case("N16_damped_huge_sag", scene("sag2", {"m": 1e60, "k": 1e-100, "g": -10.0}, '''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
k = "k"
[damping]
modal = 0.2
[gravity]
g = "g"
[initial]
x = [0.04]
[simulation]
dt = 0.01
steps = 40
record_every = 10
'''), outputs=("simulate",), features=frozenset({"regime:extreme", "damping:modal", "gravity"}),
         new="exact method, damped (modal 0.2), one mass 1e60 kg on a 1e-100 N/m spring under gravity (sag 1e161 m): "
             "x(0.1 s) = 4.06e63 m where the free fall gives -0.01 m, no float64 note (undamped: right); "
             "found by the generator (also a 13-mass chain under a constant ground acceleration, off by 7e40)", failing=False),
    Case("N17_damped_free_mass_simulate", scene("dm1", {"m": 2.0, "c": 1.0}, '''
[masses]
p = "m"
[[dampers]]
between = ["p", "wall"]
c = "c"
[initial]
v = [1.0]
'''), outputs=("simulate",),
         new="simulate of one free mass slowed by a dashpot to the wall (x = v0 m/c (1 - exp(-c t/m)) exactly): "
             "TypeError 'float() argument must be ... not complex' (also with Rayleigh alpha instead of the "
             "dashpot); found by the generator", failing=False),
    Case("N8_free_wall_chain_shape_order", scene("fw", {"m": 1.0, "k": 1.0}, '''
[chain]
n = 3
mass = "m"
k = "k"
left = "free"
right = "wall"
'''), features=frozenset({"form:chain"}),
         new="modes --json of a free-wall [chain]: shape_value lists the shape with i counted from the right "
             "end (mass 2 first) while shape_mass_normalised beside it is in mass order", failing=False),
    Case("N8_index_chain_no_shape_value", scene("idx", {"m": 1.0, "k": 1.0}, '''
[chain]
n = 3
mass = "m*(1 + i % 2)"
k = "k"
left = "wall"
right = "free"
'''), features=frozenset({"form:chain"}),
         new="modes --json of an index-dependent [chain] of 3 masses lists no shape_value (README: 'listed only "
             "for chains of at most 40 masses'); its shapes appear only as shape_mass_normalised", failing=False),
]

__all__ = ["Case", "CASES", "PULSE", "EVEN", "scene"]

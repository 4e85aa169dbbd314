"""Each axle's own peak friction in the tyre-saturation fit: why the understeer gradient needs it.

With the simplified Magic Formula per axle, F / F_z = mu sin(C atan(B alpha)), B = c / (C mu)
(c = C_alpha / F_z, components.models.tyre), each axle in a steady turn carries F / F_z = a_y / g,
so its slip angle is alpha = (C mu / c) tan(asin(a_y / (g mu)) / C), and the steady turn reads

    delta - L / R = alpha_f - alpha_r.

One mu and one C on both axles make this K h(a_y) with h(a) = g C mu tan(asin(a / (g mu)) / C),
h'(0) = 1, K = (1/c_f - 1/c_r) / g (Rajamani 3.3 per unit load): the whole understeer curve past
the linear range is K times a shape the friction alone sets. A vehicle whose front axle lets go
before its rear (a front-heavy roll-stiffness split, smaller front tyres, the lateral load transfer
that every car has: every production car is tuned to understeer at the limit) has limit understeer
that grows faster than its K predicts; with one mu the fit can only raise K to reach it, and its
shape C runs to the bound where h bends earliest. With mu_f and mu_r = rho mu_f the bend of each
axle is its own and K is again the slope at a_y = 0, the quantity the steady turns measure
(delta = L / R + K a_y in the linear range). rho = 1 is the single-friction model, so nothing is lost
where the axles let go together.

The fit's parameter is rho (``FRICTION_RATIO``); the Magic Formula's ``mu`` stays the front's
(``friction``). The linear range ends where the first axle bends (first_to_bend).
"""
from __future__ import annotations

import math
from dataclasses import replace

from agrobot.components.models.tyre import FRICTION_RATIO_BOUNDS
from agrobot.estimation import Parameter

from .driving import understeer_gradient

RATIO_BOUNDS = FRICTION_RATIO_BOUNDS       # the yaw plant's tyre_friction_ratio takes the same range


def friction_ratio() -> Parameter:
    """The free parameter rho = mu_r / mu_f of the tyre-saturation fit (1: one friction on both axles)."""
    return Parameter("friction_ratio", "1", 0.1, *RATIO_BOUNDS,
                     meaning="rear tyre friction over the front's, mu_r / mu_f (below 1 the rear lets go first)")


def first_to_bend(mu: float, ratio: float) -> tuple[float, dict[str, float], str]:
    """(the friction of the axle that bends first, min(mu_f, rho mu_f), its gradient in the fit's
    parameters ``friction`` (mu_f) and ``friction_ratio`` (rho) for the delta method on their
    covariance (FitResult.interval_of: a log that bends one axle sees its mu well and mu_f and rho
    each poorly, strongly correlated), which axle): the linear range of a steady turn ends at its bend."""
    if ratio >= 1.0:
        return mu, {"friction": 1.0}, "front"
    return mu * ratio, {"friction": ratio, "friction_ratio": mu}, "rear"


# the per-axle fit's evaluations: its ten parameters and the tyres' bend leave the 40 of the other
# fits short of converging on a log driven hard (it stops on its budget, not its tolerance)
SATURATION_EVALUATIONS = 80
BIC_MARGIN = 10.0           # as the saturation's own verdict: dBIC below -10 keeps the extra parameter
# how far the per-axle fit's fall of the RSS may exceed the Gauss-Newton prediction at rho = 1 and
# still be tried: a bend the ratio moves is not quadratic in it over [0.5, 2], and the first-order
# fall is no bound. Measured on the generated logs of the tests and the corpus's recordings: a kept
# ratio's fall was 1.4 to 4.6 times its first-order one, which was at least 0.24 of the fall needed
# (4.6 and 0.24: a racecar's log whose ratio ended on its bound 0.5, dBIC -11.2); every log whose
# first order was under 0.1 of it kept one friction
GAIN_ALLOWANCE = 10.0


def needed_fall(single) -> float:
    """The fall of the RSS the per-axle fit needs to be kept: n_eff ln(RSS_b / RSS_s) + ln(n_eff)
    < -BIC_MARGIN (one parameter more, both BICs at the one-friction fit's n_eff), so
    RSS_s - RSS_b > RSS_s (1 - exp(-(BIC_MARGIN + ln n_eff) / n_eff))."""
    n_eff = single.n_eff_total
    return single.rss_total * -math.expm1(-(BIC_MARGIN + math.log(n_eff)) / n_eff)


def axle_friction_fit(fit, gain, single, free: list, notes: list[str]):
    """(the tyre-saturation fit, its free parameters): ``single`` (one friction on both axles)
    unless the same model with rho free (``fit(free, start, evaluations)``, started from the values
    of ``single`` at rho = 1: the two fits nested, the per-axle one from the other's optimum) lowers
    the BIC by more than BIC_MARGIN, both at the n_eff of ``single`` (FitResult.bic_at: each fit's own
    n_eff moves the BIC by more than the margin where rho changes nothing), with rho inside its
    bounds (RATIO_BOUNDS are the plant's and the physical range: a rho on one is not concluded).

    The per-axle fit (SATURATION_EVALUATIONS) is run only where it can win: ``gain(free, start,
    added)`` -> (RSS, fall), the fall of the RSS rho brings at the start to first order (the
    Gauss-Newton step within the bounds with rho free less that with rho held:
    driving.gauss_newton_gain, the score test's; one Jacobian), must be at least
    needed_fall / GAIN_ALLOWANCE. Where no axle of the one-friction fit nears its bend the yaw rate
    does not move with rho and the fall is nil. The choice is said in ``notes`` with what it passed
    over."""
    free_both = [replace(q, meaning=f"front {q.meaning}") if q.name == "friction" else q for q in free]
    free_both.append(friction_ratio())
    start = {**single.values, "friction_ratio": 1.0}
    needed = needed_fall(single)
    rss, fall = gain(free_both, start, ("friction_ratio",))
    if fall * GAIN_ALLOWANCE < needed:
        notes.append(f"tyre friction: one on both axles; a rear / front ratio was not fitted: at rho = 1 it lowers "
                     f"the RSS by {100 * fall / rss:.2g} % to first order (Gauss-Newton), {GAIN_ALLOWANCE:g} times "
                     f"that is short of the {100 * needed / rss:.2g} % a dBIC below -{BIC_MARGIN:g} needs "
                     f"(passed over: the per-axle fit, {SATURATION_EVALUATIONS} evaluations)")
        return single, free
    both = fit(free_both, start, SATURATION_EVALUATIONS)
    dbic = both.bic_at(single.n_eff_total) - single.bic
    rho = both.values["friction_ratio"]
    if dbic < -BIC_MARGIN and both.at_bound(free_both[-1]):
        notes.append(f"tyre friction: one on both axles; a rear / front ratio fitted ran to its bound {rho:.3g} "
                     f"(dBIC {dbic:.0f}): a value on a bound is not concluded, so the per-axle friction is not "
                     f"identifiable from this log (the axle's range [{RATIO_BOUNDS[0]:g}, {RATIO_BOUNDS[1]:g}] is the "
                     f"yaw plant's tyre_friction_ratio's; a misfit elsewhere, e.g. a load or a trailer, may be what it took up)")
        return single, free
    if dbic < -BIC_MARGIN:
        notes.append(f"tyre friction per axle: rear / front {rho:.3g} kept (dBIC {dbic:.0f} against one friction on "
                     f"both axles, whose K {understeer_gradient(single.values['c_f'], single.values['c_r']):.3g} rad/(m/s2) is passed over: it takes up the limit "
                     f"understeer of the axle that lets go first)")
        return both, free_both
    notes.append(f"tyre friction: one on both axles (a rear / front ratio {rho:.3g} fitted changes the BIC by "
                 f"{dbic:+.1f}, not below -{BIC_MARGIN:g}: passed over)")
    return single, free

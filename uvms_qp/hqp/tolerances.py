"""Every numeric tolerance of the solve path, once, each named by what it decides.

All are relative: each says what it is relative to. The solvers' per-back-end tolerances
(``level_tol``, ``hard_tol``, the cascades' margins) are data of the registry
(:mod:`uvms_qp.hqp.registry`), whose defaults are the first two below.

**The answer.**
"""

#: A level is met when its residual is at most ``LEVEL_TOL * max(1, max |finite side|)``.
LEVEL_TOL = 1e-6
#: The box and hard rows hold when their largest violation is at most
#: ``HARD_TOL * max(1, max |finite hard side|)``.
HARD_TOL = 1e-9
#: A certified level's residual is within ``OPT_TOL * max(1, max |finite side|)`` of its optimum.
OPT_TOL = 1e-6
#: The certificate's freeze allowance of a higher level row: ``FREEZE_TOL * max(1, |a_i x|)``
#: (a level certified only without it is ``ill_posed``).
FREEZE_TOL = 1e-9

# ---------------------------------------------------------------- active and tight sides
#: A row counts as *active* (its side may carry a multiplier, its direction is restricted) when
#: it is within ``ACTIVE_TOL`` of a side, relative to ``1 + |a_i x|`` (the optimality
#: certificate of a level) or to ``max(1, max |A x|)`` (the damping screen). Any value is
#: sound for the certificate, which charges a multiplier for its distance to the side.
ACTIVE_TOL = 1e-7
#: A constraint of one QP is *tight* (may carry a multiplier in its KKT check, a variable of a
#: result sits at its bound) within ``TIGHT_TOL (1 + |side|)``.
TIGHT_TOL = 1e-9
#: A constraint of a cascade's level QP with a positive multiplier is *pinned* for the levels
#: below (kept as an equality) within ``PIN_TOL (1 + |side|)`` of its side (an inexact
#: back-end's answer sits on its active sides to about its own tolerance).
PIN_TOL = 1e-8
#: A point is feasible for one QP within ``FEAS_TOL (1 + |side|)``.
FEAS_TOL = 1e-10

# ----------------------------------------------------------------------------- stationarity
#: What a stationarity residual may keep, relative to the gradient it balances: the KKT check of
#: one QP (``max(|P z|, |q|, |C' nu|, ROUND_OFF |P| |z|)``) and the level certificate's
#: residual on variables without a box (the level's gradient).
STAT_TOL = 1e-9
#: The least scale of a QP's stationarity test, relative to ``|P| |z|`` (the terms that make up
#: ``P z``, whose round-off the test must tolerate when they cancel).
ROUND_OFF = 1e-3

# ------------------------------------------------------------------------ rank and zero rows
#: A row is dependent on the equality rows above it within ``DEPENDENT_TOL`` of their span
#: (relative distance).
DEPENDENT_TOL = 1e-9
#: A row whose norm is below ``ZERO_ROW_TOL`` of the problem's largest row counts as zero (a
#: row of norm 1e-8 with a target of 1 needs |x| ~ 1e8 to move its violation: a constant inside
#: any box, and no direction for the levels below).
ZERO_ROW_TOL = 1e-7
#: Singular values at or below ``RANK_RTOL * sigma_max`` (and ``RANK_ATOL``) count as zero in
#: the damping screen's rank decisions.
RANK_RTOL = 1e-12
RANK_ATOL = 1e-15

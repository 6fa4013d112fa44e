"""Pink (``pin-pink``) as a controller with the ``step(state, t)`` interface, timed side by side.

Pink solves one weighted differential-IK QP per tick over the Pinocchio tangent space:

    min_v  sum_tasks cost * |J_task v dt + gain_task e_task|^2  +  damping |v dt|^2
    s.t.   G(q) v dt <= h(q)            (its configuration and velocity limits)

which is one weighted level: no strict priorities. Here the tasks are a ``FrameTask`` on the
tracked frame and a ``PostureTask`` holding the configuration the controller started from; the
limits are Pink's ``ConfigurationLimit`` (joint position limits through ``dt``, gain matching our
``JointPositionBounds``), ``VelocityLimit`` (the model's rate limits) and a constant rate box
carrying the benchmark problem's own rate bounds (vehicle and joint), so both libraries enforce
the same box. A task gain ``K`` [1/s] of ours is Pink's dimensionless gain ``K dt`` (Pink's
``v dt`` is our ``zeta dt``).

Only models whose decision vector is the whole Pinocchio velocity (every vehicle DOF actuated, or
a fixed base) can be expressed: :func:`pink_supported` checks it.
"""

from __future__ import annotations

import importlib.util
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..errors import InputError


def pink_available() -> bool:
    """True when ``pin-pink`` can be imported (checked without importing it)."""
    return importlib.util.find_spec("pink") is not None


def pink_supported(model: Any, frame: str = "tool") -> str | None:
    """None when Pink can express a problem on ``model`` tracking ``frame``, else the reason."""
    if int(model.nv) != int(model.pin_model.nv):
        return "passive vehicle DOFs (Pink optimises every Pinocchio velocity)"
    if not model.pin_model.existFrame(frame):
        return f"frame {frame!r} not in the Pinocchio model"
    return None


@dataclass
class PinkStep:
    """Result of one Pink tick (the fields the simulator and the benchmark read).

    Attributes:
        zeta: Velocity (nv,) [m/s, rad/s] (zero when Pink failed).
        status: ``"optimal"`` or ``"backend_error"``.
        step_time: Wall time [s] of the tick (kinematics + QP).
        message: Failure detail.
    """

    zeta: FloatArray
    status: str
    step_time: float
    message: str = ""
    task_residuals: dict[str, tuple[float, str]] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when Pink returned a solution."""
        return self.status == "optimal"


class _RateBox:
    """A constant box ``lower <= v <= upper`` as Pink limit inequalities ``G v dt <= h``."""

    def __init__(self, lower: FloatArray, upper: FloatArray) -> None:
        n = lower.size
        eye = np.eye(n)
        hi, lo = np.isfinite(upper), np.isfinite(lower)
        self._G = np.vstack([eye[hi], -eye[lo]])
        self._b = np.concatenate([upper[hi], -lower[lo]])

    def compute_qp_inequalities(self, configuration: Any, dt: float) -> Any:
        if not self._b.size:
            return None
        return self._G, dt * self._b


class PinkController:
    """Pink differential IK stepping like :class:`~uvms_qp.controller.Controller`.

    Args:
        model: Fully actuated (or fixed-base) :class:`~uvms_qp.model.Model`.
        dt: Control period [s].
        frame: Tracked frame.
        position: Fixed target position (3,) [m, world] (or use :meth:`track`).
        rotation: Fixed target rotation (3, 3) (None: position only, orientation cost 0).
        trajectory: Object with ``sample(t)`` giving the target position.
        gain: Our task gain K [1/s] (Pink gain ``min(1, K dt)``).
        posture_cost: Cost of the posture task relative to the frame task.
        position_gain: Gain of the joint-position limit (Pink's ``config_limit_gain``).
        rate_lower: Extra constant lower rate bounds (nv,), ``-inf`` for none.
        rate_upper: Extra constant upper rate bounds (nv,), ``+inf`` for none.
        qp_solver: qpsolvers back-end Pink uses (``"daqp"`` by default, as our native solver).

    Raises:
        InputError: a model Pink cannot express (see :func:`pink_supported`).
    """

    solver_name = "pink"

    def __init__(self, model: Any, dt: float, *, frame: str = "tool", position: Any = None,
                 rotation: Any = None, trajectory: Any = None, gain: float = 1.0,
                 posture_cost: float = 1e-3, position_gain: float = 0.5,
                 rate_lower: Any = None, rate_upper: Any = None,
                 qp_solver: str = "daqp") -> None:
        import pink
        from pink.limits import ConfigurationLimit, VelocityLimit
        from pink.tasks import FrameTask, PostureTask

        reason = pink_supported(model, frame)
        if reason is not None:
            raise InputError(f"pink: cannot express model {model.name!r}: {reason}")
        self._pink = pink
        self.model = model
        self.dt = float(dt)
        self.qp_solver = qp_solver
        pm = model.pin_model
        self._pm = pm
        self._data = pm.createData()
        self.frame_task = FrameTask(frame, position_cost=1.0,
                                    orientation_cost=1.0 if rotation is not None else 0.0,
                                    gain=min(1.0, float(gain) * self.dt))
        self.posture_task = PostureTask(cost=float(posture_cost))
        self.tasks = [self.frame_task, self.posture_task]
        nv = int(model.nv)
        lo = np.full(nv, -np.inf) if rate_lower is None else np.asarray(rate_lower, float)
        hi = np.full(nv, np.inf) if rate_upper is None else np.asarray(rate_upper, float)
        self.limits = [ConfigurationLimit(pm, config_limit_gain=float(position_gain)),
                       VelocityLimit(pm), _RateBox(lo, hi)]
        self.position = None if position is None else np.asarray(position, float)
        self.rotation = None if rotation is None else np.asarray(rotation, float)
        self.trajectory = trajectory
        self._posture_set = False

    def reset(self) -> None:
        """Forget the posture reference (taken again at the next step)."""
        self._posture_set = False

    def track(self, trajectory: Any) -> None:
        """Follow ``trajectory`` (anything with ``sample(t)``)."""
        self.trajectory = trajectory

    def _target(self, t: float) -> Any:
        import pinocchio as pin

        position: Any
        rotation: Any
        if self.trajectory is not None:
            sample = self.trajectory.sample(t)
            position = np.asarray(sample.position, float)
            rotation = getattr(sample, "rotation", None) if self.rotation is not None else None
        else:
            position, rotation = self.position, self.rotation
        if rotation is None:
            rotation = np.eye(3)
        return pin.SE3(np.asarray(rotation, float), np.asarray(position, float))

    def step(self, state: Any, t: float = 0.0) -> PinkStep:
        """One Pink tick at ``state.q``: kinematics, task targets, QP (all timed)."""
        start = time.perf_counter()
        configuration = self._pink.Configuration(self._pm, self._data, state.q, copy_data=False)
        if not self._posture_set:
            self.posture_task.set_target(state.q)
            self._posture_set = True
        self.frame_task.set_target(self._target(float(t)))
        try:
            v = self._pink.solve_ik(configuration, self.tasks, self.dt, solver=self.qp_solver,
                                    limits=self.limits, safety_break=False)
            status, message = "optimal", ""
            if not np.all(np.isfinite(v)):
                status, message = "backend_error", "non-finite velocity"
        except Exception as exc:  # Pink raises NoSolutionFound and friends
            v = np.zeros(int(self.model.nv))
            status, message = "backend_error", f"{type(exc).__name__}: {exc}"
        elapsed = time.perf_counter() - start
        return PinkStep(np.asarray(v, dtype=np.float64), status, elapsed, message)


def rate_box(constraints: Any, state: Any, dt: float, nv: int) -> tuple[FloatArray, FloatArray]:
    """Intersection of the constant rate boxes (joint and vehicle rate bounds) of constraints."""
    lower, upper = np.full(nv, -np.inf), np.full(nv, np.inf)
    for c in constraints:
        if getattr(c, "type_name", "") in ("joint_velocity_bounds", "vehicle_rate_bounds"):
            lo, hi = c.box(state, dt)
            np.maximum(lower, lo, out=lower)
            np.minimum(upper, hi, out=upper)
    return lower, upper


def position_gain(constraints: Any) -> float:
    """Gain of the joint position bounds among ``constraints`` (0.5, Pink's default, if none)."""
    for c in constraints:
        if getattr(c, "type_name", "") == "joint_position_bounds":
            return float(c.gain)
    return 0.5


__all__ = ["PinkController", "PinkStep", "pink_available", "pink_supported", "position_gain",
           "rate_box"]

"""UVMS kinematic models on Pinocchio: vehicle + arm + frames, and per-tick kinematic states.

Public names: :class:`Model` (``from_dh``, ``from_urdf``), :class:`State`, :func:`load_model`,
:func:`bundled_models`, :func:`model_names`, :func:`register_model`, :class:`Vehicle`,
:class:`DHRow`.
"""

from __future__ import annotations

from .bundled import bundled_models
from .dh import DHRow
from .model import Model
from .registry import load_model, model_names, register_model, unregister_model
from .state import State
from .transforms import flu_to_frd, transform
from .vehicle import Vehicle

__all__ = [
    "DHRow",
    "Model",
    "State",
    "Vehicle",
    "bundled_models",
    "flu_to_frd",
    "load_model",
    "model_names",
    "register_model",
    "transform",
    "unregister_model",
]

"""Models by name: the bundled ones, models registered at run time, and plug-in packages.

:func:`load_model` resolves a name in this order:

1. a bundled model (:func:`~uvms_qp.model.bundled.bundled_models`);
2. a model registered in this process with :func:`register_model` (what ``uvms-qp
   --model-path FILE`` does for a model file);
3. an entry point of the group :data:`ENTRY_POINT_GROUP` (``uvms_qp.models``) declared by an
   installed package, whose object is a function returning a :class:`~uvms_qp.model.Model`::

       [project.entry-points."uvms_qp.models"]
       my_rov = "my_package.models:my_rov"

A name means one model: registering a name that is already bundled, registered or declared by an
entry point is an error.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from importlib import metadata
from typing import Any

from ..errors import InputError, ModelError, UnknownModelError
from .bundled import bundled_entry, bundled_models
from .model import Model

#: Entry-point group through which installed packages name their models.
ENTRY_POINT_GROUP = "uvms_qp.models"


@dataclass(frozen=True)
class ModelEntry:
    """A model name and how to build it.

    Attributes:
        name: The name scenarios use (``model = "name"``).
        build: Function returning a fresh :class:`~uvms_qp.model.Model`.
        summary: One line on what the model is.
        origin: ``"bundled"``, ``"registered"`` or ``"entry point <value>"``.
    """

    name: str
    build: Callable[[], Model]
    summary: str
    origin: str


_REGISTERED: dict[str, ModelEntry] = {}


def _entry_points() -> dict[str, metadata.EntryPoint]:
    return {point.name: point for point in metadata.entry_points(group=ENTRY_POINT_GROUP)}


def _first_line(text: str | None) -> str:
    return (text or "").strip().split("\n", 1)[0].strip()


def register_model(
    name: str, build: Callable[[], Model], summary: str = "", *, replace: bool = False
) -> None:
    """Make ``build`` loadable as ``load_model(name)`` (and ``model = "name"`` in scenarios).

    Args:
        name: The model name: a non-empty string without spaces, not a bundled model's name.
        build: Function returning a fresh :class:`~uvms_qp.model.Model`.
        summary: One line shown by ``uvms-qp models`` (default: the first line of ``build``'s
            docstring).
        replace: Allow replacing a model registered earlier under the same name.

    Raises:
        InputError: a malformed name, a ``build`` that is not callable, or a name that is bundled,
            declared by an entry point, or already registered (without ``replace``).
    """
    if not isinstance(name, str) or not name or name != name.strip() or " " in name:
        raise InputError(f"model name: expected a non-empty string without spaces, got {name!r}")
    if not callable(build):
        raise InputError(f"model {name!r}: build must be a function returning a Model, "
                         f"got {type(build).__name__}")
    if name in bundled_models():
        raise InputError(f"model {name!r} is a bundled model; choose another name")
    if name in _entry_points():
        raise InputError(f"model {name!r} is declared by an installed package "
                         f"({ENTRY_POINT_GROUP} entry point); choose another name")
    if name in _REGISTERED and not replace:
        raise InputError(f"model {name!r} is already registered")
    text = summary or _first_line(getattr(build, "__doc__", None))
    _REGISTERED[name] = ModelEntry(name, build, text, "registered")


def unregister_model(name: str) -> None:
    """Forget a model registered with :func:`register_model` (no error when it is not)."""
    _REGISTERED.pop(name, None)


def model_names() -> list[str]:
    """Every loadable name: bundled, then registered, then entry points (each group sorted)."""
    return [*bundled_models(), *sorted(_REGISTERED), *sorted(_entry_points())]


def model_entry(name: str) -> ModelEntry:
    """The entry of a model name (see the module docstring for the lookup order).

    Raises:
        UnknownModelError: no model of that name (the message lists the known ones).
        ModelError: an entry point that cannot be imported.
    """
    if isinstance(name, str):
        if name in bundled_models():
            entry = bundled_entry(name)
            return ModelEntry(name, entry.build, entry.summary, "bundled")
        if name in _REGISTERED:
            return _REGISTERED[name]
        point = _entry_points().get(name)
        if point is not None:
            try:
                build = point.load()
            except Exception as exc:  # any import failure of a third-party package
                raise ModelError(f"model {name!r}: cannot import entry point {point.value!r}: "
                                 f"{type(exc).__name__}: {exc}") from exc
            return ModelEntry(name, build, _first_line(getattr(build, "__doc__", None)),
                              f"entry point {point.value}")
    raise UnknownModelError(name, model_names())


def load_model(name: str) -> Model:
    """Build the model called ``name`` (a fresh instance on every call).

    Raises:
        UnknownModelError: no model of that name (the message lists the known ones).
        ModelError: the model's function failed or returned something else than a Model.
    """
    entry = model_entry(name)
    model: Any = entry.build()
    if not isinstance(model, Model):
        raise ModelError(f"model {name!r} ({entry.origin}): expected a Model from "
                         f"{getattr(entry.build, '__qualname__', entry.build)!r}, got "
                         f"{type(model).__name__}")
    return model

"""Tracker registry: ``create_tracker(name, seed=..., **params)``.

Each entry maps a name to a tracker class with a typed :class:`~pftrack.params.Params`
dataclass.  Keyword arguments that name a parameter are validated by that
dataclass; a few non-parameter keywords (``detector``) go to the constructor.
Unknown names raise :class:`~pftrack.errors.ParameterError` with suggestions.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..params import Params
from .base import Tracker


@dataclass(frozen=True)
class TrackerSpec:
    name: str
    cls: type[Tracker]
    summary: str
    family: str = "pftrack"  # "pftrack" | "baseline" | "opencv"
    extra_kwargs: tuple[str, ...] = ()
    available: Callable[[], bool] = lambda: True

    @property
    def params_cls(self) -> type[Params]:
        return self.cls.Params


_REGISTRY: dict[str, TrackerSpec] = {}


def register(name: str, cls: type[Tracker], summary: str, *, family: str = "pftrack",
             extra_kwargs: tuple[str, ...] = (), available: Callable[[], bool] | None = None) -> None:
    if name in _REGISTRY:
        raise ValueError(f"tracker {name!r} is already registered")
    _REGISTRY[name] = TrackerSpec(name, cls, summary, family, tuple(extra_kwargs), available or (lambda: True))


def get_spec(name: str) -> TrackerSpec:
    _ensure_loaded()
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):  # TypeError: an unhashable name
        if not isinstance(name, str):
            kind = type(name).__name__
            raise ParameterError(f"a tracker is named by a string (see 'pftrack list'), not {kind}") from None
        close = difflib.get_close_matches(name, sorted(_REGISTRY), n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise ParameterError(f"unknown tracker '{name}'{hint} (see 'pftrack list')") from None


def list_trackers(family: str | None = None) -> list[TrackerSpec]:
    _ensure_loaded()
    return [s for s in _REGISTRY.values() if family is None or s.family == family]


def tracker_names(family: str | None = None) -> list[str]:
    return [s.name for s in list_trackers(family)]


def create_tracker(name: str, *, seed: int | None = None, rng: np.random.Generator | None = None,
                   params: Params | Mapping[str, Any] | None = None, **kwargs: Any) -> Tracker:
    """Create a registered tracker.

    Parameters
    ----------
    name : registry name (``pftrack list`` shows them all).
    seed, rng : the randomness source; the same seed gives bit-identical results.
    params : a Params instance or a mapping of parameter values.
    **kwargs : parameter values (validated), or constructor extras such as ``detector``.

    Every tracker also takes ``monitor=True`` (in ``params`` too): its boxes are judged by the colour PFs' loss
    test, which raises ``lost`` (:class:`~pftrack.trackers.monitor.Monitored`); ``monitor_cues="fused"`` adds
    fusion-pf's structural score to that test. ``grey_restart=N`` starts a tracker again on grey features once N
    frames in a row are grey (:class:`~pftrack.trackers.input_switch.GreyRestarted`).
    """
    spec = get_spec(name)
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise ParameterError(f"seed must be an integer >= 0 or None, got {seed!r}")
    if not spec.available():
        raise ParameterError(f"tracker '{name}' is not available in this installation")
    from .monitor import Monitored, grey_restart_for, split_wrapper_options, wrapper_options

    extras = {k: kwargs.pop(k) for k in list(kwargs) if k in spec.extra_kwargs}
    mapping = None if isinstance(params, Params) else params  # wrapper options come with a mapping, not a Params
    wrap = wrapper_options(mapping, kwargs)
    grey_restart = grey_restart_for(spec.cls, mapping, kwargs)
    kwargs = split_wrapper_options(kwargs)[1]
    if isinstance(params, Params):
        if kwargs:
            params = params.replace(**kwargs)
    else:
        params = spec.params_cls.from_mapping(split_wrapper_options(dict(params or {}))[1], **kwargs)
    if not isinstance(params, spec.params_cls):
        raise ParameterError(f"tracker '{name}' takes {spec.params_cls.__name__}, got {type(params).__name__}")
    tracker = spec.cls(params, seed=seed, rng=rng, **extras)
    if grey_restart:
        from .input_switch import GreyRestarted

        tracker = GreyRestarted(tracker, grey_restart)
    if not wrap.monitor:
        return tracker
    return Monitored(tracker, wrap.monitor_params())


_loaded = False


def _ensure_loaded() -> None:
    global _loaded
    if _loaded:
        return
    _loaded = True
    from .builtin import BUILTIN

    for name, cls, summary, options in BUILTIN:
        register(name, cls, summary, **options)
    # Trackers of the application packages (layer 5) register themselves through a module-level
    # ``REGISTRY_ENTRIES`` list; they are imported by name so that this layer never imports them statically.
    import importlib

    for module in APPLICATION_TRACKERS:
        for name, cls, summary, options in importlib.import_module(module).REGISTRY_ENTRIES:
            register(name, cls, summary, **options)
    _load_plugins()


#: Modules of the application packages that contribute trackers to the registry.
APPLICATION_TRACKERS: tuple[str, ...] = ("pftrack.surfaces.tracker", "pftrack.segmentation.tracker")

#: The entry-point group through which installed packages add trackers (:func:`_load_plugins`).
PLUGIN_GROUP = "pftrack.trackers"


def _load_plugins() -> None:
    """Trackers of other installed packages: every entry point of the ``pftrack.trackers`` group names a module
    (or any object) with a ``REGISTRY_ENTRIES`` list of ``(name, class, summary, options)``, or a callable that
    returns such a list. The family defaults to ``"plugin"``. A plugin that fails to load, or whose names are
    taken, is skipped with a warning: it never breaks the built-in trackers."""
    import warnings
    from importlib.metadata import entry_points

    for ep in entry_points(group=PLUGIN_GROUP):
        try:
            obj = ep.load()
            entries = obj.REGISTRY_ENTRIES if hasattr(obj, "REGISTRY_ENTRIES") else obj()
            entries = list(entries)
            names = [e[0] for e in entries]
            if len(set(names)) != len(names):
                raise ValueError(f"a name is listed twice in {names}")
            for name, cls, summary, options in entries:  # checked before any is registered
                if name in _REGISTRY:
                    raise ValueError(f"tracker {name!r} is already registered")
                if not (isinstance(cls, type) and issubclass(cls, Tracker)):
                    raise TypeError(f"{name!r}: {cls!r} is not a pftrack Tracker subclass")
                unknown = set(dict(options)) - {"family", "extra_kwargs", "available"}
                if unknown:
                    raise TypeError(f"{name!r}: unknown options {sorted(unknown)}")
        except Exception as exc:  # noqa: BLE001 - a third party's failure is reported, not raised
            warnings.warn(f"tracker plugin {ep.name!r} ({ep.value}) not loaded: {type(exc).__name__}: {exc}",
                          stacklevel=2)
            continue
        for name, cls, summary, options in entries:
            register(name, cls, summary, **{"family": "plugin", **dict(options)})

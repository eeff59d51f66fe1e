"""Engine files (TOML) and the built-in presets.

An engine file has the top-level keys ``name``, ``strokes`` and ``cylinders`` and the
tables ``[geometry]``, ``[masses]``, ``[crankshaft]``, ``[layout]``, ``[pressure]``,
``[operating]`` and, optionally, ``[articulated]``, ``[friction]``, ``[torsion]`` (the
multi-mass torsional chain, :class:`rotor.Torsion`) and the list ``[[counterweights]]``
(one table per counterweight: ``web``, ``mass_kg``, ``radius_m``, ``angle_deg``); each
becomes the module of the same name on :class:`rotor.Engine`. Unknown keys and tables are
errors (a typo must not be ignored), and so are values of the wrong type, and values
outside the ranges of real engines, naming the unit a value reads as (a pressure in bar,
a table in MPa, a stroke in mm, a mass in grams: :func:`rotor.engine.plausible.check_engine_file_units`).

``[torsion]``'s constant inertias must sum to ``[crankshaft] inertia_kgm2`` (to 1e-6
relative): the chain is the same crankshaft, flywheel and attachments split into masses,
and rotor adds the rods and pistons to the throws itself, so that very stiff shafts give
the rigid model.
"""

from __future__ import annotations

import dataclasses
import difflib
import os
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import EngineError
from .friction import Friction
from .model import Articulated, Counterweights, Crankshaft, Engine, Geometry, Layout, Masses, Operating, Torsion
from .plausible import check_engine_file_units
from .pressure import PRESSURE_KINDS

__all__ = ["load_engine", "engine_from_dict", "preset_names", "preset_path", "MAX_FILE_BYTES"]

MAX_FILE_BYTES = 16 * 1024**2
"""The largest engine file read [bytes]: a pressure table of a million points fits well within."""

MAX_NESTING = 16
"""The deepest nesting of tables and lists an engine description may have: an engine file
nests four levels at most (``[[counterweights]]``, a table, a key, a list of numbers)."""

_NUM, _NUMS, _INTS, _STR, _INT, _STRS, _NUM_OR_NUMS = (
    "a number",
    "a list of numbers",
    "a list of whole numbers",
    "a string",
    "a whole number",
    "a list of strings",
    "a number or a list of numbers",
)

_TOP = {"name": _STR, "strokes": _INT, "cylinders": _INT}
_TABLES = {
    "geometry": Geometry,
    "masses": Masses,
    "crankshaft": Crankshaft,
    "layout": Layout,
    "operating": Operating,
    "articulated": Articulated,
    "friction": Friction,
    "torsion": Torsion,
}
_REQUIRED_TABLES = ("geometry", "masses", "crankshaft", "layout", "operating")
_LIST_KEYS = {
    "throw_angles_deg": _NUMS,
    "bank_angles_deg": _NUMS,
    "firing_order": _INTS,
    "angle_deg": _NUMS,
    "pressure_pa": _NUMS,
    "slaves": _INTS,
    "masters": _INTS,
    "throws": _INTS,
    "main_journals": _INT,
    "inertias_kgm2": _NUMS,
    "stiffnesses_Nm_per_rad": _NUMS,
    "absolute_damping_Nms_per_rad": _NUMS,
    "relative_damping_Nms_per_rad": _NUMS,
    "modal_damping_ratio": _NUM_OR_NUMS,
    "names": _STRS,
    "throw_masses": _INTS,
    "load_mass": _INT,
}

TORSION_SUM_RTOL = 1e-6
"""How closely ``[torsion] inertias_kgm2`` must sum to ``[crankshaft] inertia_kgm2`` [-]."""
_COUNTERWEIGHT_KEYS = {
    "web": (_INT, True),
    "mass_kg": (_NUM, True),
    "radius_m": (_NUM, True),
    "angle_deg": (_NUM, False),
}


def _suggest(word, options):
    close = difflib.get_close_matches(word, list(options), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _fields(cls):
    """{key: required?} of a module's file keys."""
    out = {}
    for f in dataclasses.fields(cls):
        if f.name == "kind":
            continue
        no_default = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        out[f.name] = no_default
    return out


def _typed(table, key, value, kind):
    where = f"[{table}] {key}" if table else key
    if kind == _STR:
        if not isinstance(value, str):
            raise EngineError(f"{where} = {value!r}: expected {kind}")
        return value
    if kind == _INT:
        if isinstance(value, bool) or not isinstance(value, int):
            raise EngineError(f"{where} = {value!r}: expected {kind}")
        return value
    if kind == _NUM_OR_NUMS:
        kind = _NUMS if isinstance(value, list) else _NUM
    if kind == _NUM:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise EngineError(f"{where} = {value!r}: expected {kind}")
        return float(value)
    if not isinstance(value, list):
        raise EngineError(f"{where} = {value!r}: expected {kind}")
    if kind == _STRS:
        for i, v in enumerate(value, 1):
            if not isinstance(v, str):
                raise EngineError(f"{where}: item {i} is {v!r}, expected a string")
        return list(value)
    want_int = kind == _INTS
    for i, v in enumerate(value, 1):
        ok = isinstance(v, int) if want_int else isinstance(v, (int, float))
        if isinstance(v, bool) or not ok:
            raise EngineError(f"{where}: item {i} is {v!r}, expected {'a whole number' if want_int else 'a number'}")
    return [int(v) for v in value] if want_int else np.asarray(value, dtype=np.float64)


def _build(table, cls, data):
    if not isinstance(data, dict):
        raise EngineError(f"[{table}] must be a table, got {data!r}")
    fields = _fields(cls)
    kwargs = {}
    for key, value in data.items():
        if key not in fields:
            raise EngineError(f"[{table}] {key}: unknown key{_suggest(key, fields)}; known keys: {', '.join(fields)}")
        kwargs[key] = _typed(table, key, value, _LIST_KEYS.get(key, _NUM))
    for key, required in fields.items():
        if required and key not in kwargs:
            raise EngineError(f"[{table}] {key} is missing")
    return cls(**kwargs)


def _build_pressure(data, strokes):
    data = dict(data)
    kind = data.pop("kind", None)
    if kind is None:
        raise EngineError(f"[pressure] kind is missing: one of {', '.join(map(repr, PRESSURE_KINDS))}")
    if kind not in PRESSURE_KINDS:
        raise EngineError(
            f"[pressure] kind = {kind!r}: unknown{_suggest(str(kind), PRESSURE_KINDS)}; "
            f"one of {', '.join(map(repr, PRESSURE_KINDS))}"
        )
    if kind == "table":
        a, p = data.get("angle_deg"), data.get("pressure_pa")
        cycle = 360 * strokes / 2 if strokes in (2, 4) else None
        # a closing point at the full cycle that repeats the 0° point is redundant: drop it
        if (
            cycle is not None
            and isinstance(a, list)
            and isinstance(p, list)
            and len(a) == len(p)
            and len(a) > 1
            and a[0] == 0
            and a[-1] == cycle
            and p[-1] == p[0]
        ):
            data["angle_deg"], data["pressure_pa"] = a[:-1], p[:-1]
    return _build("pressure", PRESSURE_KINDS[kind], data)


def _build_counterweights(data):
    """``[[counterweights]]``: a list of tables, one per counterweight."""
    if not isinstance(data, list) or not all(isinstance(d, dict) for d in data):
        raise EngineError(
            "[[counterweights]] must be a list of tables, one per counterweight: "
            "[[counterweights]] web = 1, mass_kg = 1.2, radius_m = 0.05, angle_deg = 180"
        )
    if not data:
        return None
    cols: dict[str, list] = {"web": [], "mass_kg": [], "radius_m": [], "angle_deg": []}
    for i, item in enumerate(data, 1):
        for key in item:
            if key not in _COUNTERWEIGHT_KEYS:
                raise EngineError(
                    f"[[counterweights]] {i}: {key}: unknown key{_suggest(key, _COUNTERWEIGHT_KEYS)}; "
                    f"known keys: {', '.join(_COUNTERWEIGHT_KEYS)}"
                )
        for key, (kind, required) in _COUNTERWEIGHT_KEYS.items():
            if key not in item:
                if required:
                    raise EngineError(f"[[counterweights]] {i}: {key} is missing")
                cols[key].append(180.0)  # opposite its throw
                continue
            cols[key].append(_typed("", f"[[counterweights]] {i}: {key}", item[key], kind))
    try:
        return Counterweights(
            webs=cols["web"],
            mass_kg=np.asarray(cols["mass_kg"]),
            radius_m=np.asarray(cols["radius_m"]),
            angle_deg=np.asarray(cols["angle_deg"]),
        )
    except EngineError as e:
        raise EngineError(f"[[counterweights]]: {e}") from None


def _check_nesting(data: dict) -> None:
    """Refuse tables and lists nested deeper than :data:`MAX_NESTING`, naming the key where
    it happens (checked without recursion: a value nested thousands deep is refused, not a
    ``RecursionError`` in whatever reads or prints it later)."""
    stack: list[tuple[Any, str, int]] = [(data, "", 0)]
    while stack:
        value, key, depth = stack.pop()
        if depth > MAX_NESTING:
            raise EngineError(
                f"{key or 'the engine description'}: nested more than {MAX_NESTING} levels deep; an engine file's "
                "values are numbers, strings and lists of them, in tables (see `rotor presets`)"
            )
        if isinstance(value, dict):
            stack.extend((v, k if not key else f"{key}.{k}", depth + 1) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((v, key, depth + 1) for v in value)


def engine_from_dict(data: dict) -> Engine:
    """Build and validate an :class:`rotor.Engine` from the parsed contents of an engine file.

    **Arguments:** ``data``: the file's tables and keys as ``tomllib`` reads them (units as
    the keys' names say, e.g. ``data["geometry"]["bore_m"]`` in metres).

    **Raises:** :class:`rotor.EngineError` (a ``ValueError``) naming the key and the problem,
    also for tables or lists nested deeper than :data:`MAX_NESTING`.
    """
    if not isinstance(data, dict):
        raise EngineError("an engine description must be a table of keys")
    _check_nesting(data)
    known = set(_TOP) | set(_TABLES) | {"pressure", "counterweights"}
    for key in data:
        if key not in known:
            kind = "table" if isinstance(data[key], dict) else "key"
            raise EngineError(f"{key}: unknown {kind}{_suggest(key, known)}; known: {', '.join(sorted(known))}")
    top = {}
    for key, kind in _TOP.items():
        if key not in data:
            raise EngineError(f"{key} is missing (a top-level key)")
        top[key] = _typed("", key, data[key], kind)
    for table in _REQUIRED_TABLES:
        if table not in data:
            raise EngineError(f"[{table}] is missing")
    parts = {t: _build(t, _TABLES[t], data[t]) for t in _TABLES if t in data}
    if "pressure" in data:
        if not isinstance(data["pressure"], dict):
            raise EngineError(f"[pressure] must be a table, got {data['pressure']!r}")
        parts["pressure"] = _build_pressure(data["pressure"], top["strokes"])
    if "counterweights" in data:
        parts["counterweights"] = _build_counterweights(data["counterweights"])
    if "torsion" in data:
        _check_torsion_sum(parts["torsion"], parts["crankshaft"])
    check_engine_file_units(data)
    return Engine(**top, **parts)


def _check_torsion_sum(torsion: Torsion, crankshaft: Crankshaft) -> None:
    """``[torsion] inertias_kgm2`` split ``[crankshaft] inertia_kgm2`` into masses."""
    total = float(np.sum(np.asarray(torsion.inertias_kgm2)))
    J = float(crankshaft.inertia_kgm2)
    if not abs(total - J) <= TORSION_SUM_RTOL * J:
        raise EngineError(
            f"[torsion] inertias_kgm2 sum to {total:.7g} kg·m², but [crankshaft] inertia_kgm2 = {J:.7g}: the chain's "
            "constant inertias (without the rods and pistons, which rotor adds to the throws) must sum to the "
            f"crankshaft's, to {TORSION_SUM_RTOL:g} relative (change one of them by {J - total:+.7g} kg·m²)"
        )


def preset_names() -> list[str]:
    """Names of the built-in engines (``rotor.load_engine(name)``)."""
    files = resources.files("rotor.presets")
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


def preset_path(name: str):
    """The packaged TOML file of a preset."""
    return resources.files("rotor.presets") / f"{name}.toml"


def load_engine(path_or_name: str | os.PathLike[str]) -> Engine:
    """Load an engine from a TOML file or a preset name.

    **Arguments:** ``path_or_name``: a path to an engine file, or one of
    :func:`preset_names` (``"4chn15"``, ``"tue-single"``, ``"mwm6"``, ``"v8"``).

    **Returns:** a validated :class:`rotor.Engine`.

    The file is UTF-8 text (a byte-order mark at its start is accepted), at most
    :data:`MAX_FILE_BYTES` long.

    **Raises:** :class:`rotor.EngineError` (a ``ValueError``) for a missing, empty or
    malformed file, a directory, text that is not UTF-8, or arrays and tables nested too
    deeply, naming the file (the user's path), the key and the problem; a
    :class:`TypeError` if ``path_or_name`` is not a string or path.
    """
    if isinstance(path_or_name, bytes) or not isinstance(path_or_name, (str, os.PathLike)):
        raise TypeError(
            f"load_engine(path_or_name): expected a path or a preset name (a str or os.PathLike), got "
            f"{type(path_or_name).__name__} {path_or_name!r:.40}"
        )
    path = Path(path_or_name)
    name = str(path_or_name)
    if not name.strip():
        raise EngineError("engine: an empty name; give an engine file (.toml) or a preset name (rotor.preset_names())")
    if path.suffix != ".toml" and name in preset_names():
        text_source: Path | Any = preset_path(name)
        label = f"preset {name!r}"
    elif path.is_file():
        text_source = path
        label = str(path)
    elif path.is_dir():
        raise EngineError(f"{name}: is a directory, not an engine file; give the .toml file inside it or a preset name")
    elif path.suffix == ".toml" or os.sep in name:
        raise EngineError(
            f"{name}: neither an engine file nor a preset (no such file); presets: {', '.join(preset_names())}"
        )
    else:
        raise EngineError(f"{name}: neither an engine file nor a preset; presets: {', '.join(preset_names())}")
    try:
        size = text_source.stat().st_size if isinstance(text_source, Path) else 0
        if size > MAX_FILE_BYTES:
            raise EngineError(
                f"{label}: {size / 1e6:.3g} MB is far too large for an engine file (at most "
                f"{MAX_FILE_BYTES / 1e6:g} MB): is it the engine's TOML file?"
            )
        raw = text_source.read_bytes()
        text = raw.decode("utf-8-sig")  # a byte-order mark at the start is accepted
        if not text.strip():
            raise EngineError(
                f"{label}: the file is empty; an engine file needs name, strokes, cylinders and the tables "
                "[geometry], [masses], [crankshaft], [layout] and [operating] (see `rotor presets`)"
            )
        if "\x00" in text:
            raise EngineError(f"{label}: not a TOML file (it holds NUL bytes: a binary file?)")
        data = tomllib.loads(text)
    except RecursionError:  # tomllib reads nested arrays and inline tables by recursion
        raise EngineError(
            f"{label}: not a usable engine file: its arrays or inline tables are nested too deeply to read (an "
            f"engine file nests {MAX_NESTING} levels at most)"
        ) from None
    except UnicodeDecodeError as e:
        raise EngineError(
            f"{label}: not a TOML file: byte {e.start} is not UTF-8 text (save the file as UTF-8)"
        ) from None
    except tomllib.TOMLDecodeError as e:
        raise EngineError(f"{label}: not a valid TOML file: {e}") from None
    except OSError as e:
        raise EngineError(f"{label}: cannot read: {e.strerror}") from None
    try:
        return engine_from_dict(data)
    except EngineError as e:
        raise EngineError(f"{label}: {e}") from None
    except TypeError as e:  # every value was typed on the way in: this is not the user's
        raise EngineError(f"{label}: {e}") from None

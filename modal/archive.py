"""HDF5 result archives: any result dataclass in, the same dataclass out.

Layout (documented in the README)::

    /                     @schema="modalbal-archive" @schema_version="1.0"
                          @software_version @created (ISO 8601, UTC)
    /scene                string dataset: the scene text, verbatim (when given)
    /<item>/              one group per stage or result, @inputs_hash when given
        <field>           datasets with a ``units`` attribute derived from the
                          field name (``_hz`` → Hz, ``_n_per_m`` → N/m, …)

Every node carries ``@__type__`` (``dataclass`` with ``@__class__``, ``ndarray``,
``float``, ``str``, ``tuple``, ``dict``, ``none``, ``frf``…) so that
:func:`read_archive` rebuilds the same Python objects; arrays come back bit for
bit. Nothing is pickled, and only classes of ``modal`` and ``balancer`` are
rebuilt, and a result's numbers are read only with the units they are written with
(an archive of another tool under the same names, or edited, is refused). Files are written to a temporary file beside the target, closed,
reopened and checked, then renamed over it.
"""
from __future__ import annotations

import dataclasses
import importlib
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import h5py
import numpy as np

from .errors import ArchiveError
from .io.hdf5 import SCHEMA, SCHEMA_VERSION, check_schema, read_frf_group, write_frf_group, write_root_attrs

__all__ = ["SCHEMA", "SCHEMA_VERSION", "Archive", "write_archive", "read_archive", "write_node", "read_node",
           "read_warnings", "units_of"]

_ALLOWED_MODULES = ("modal.", "balancer.")
_COMPRESS_BYTES = 16384  # gzip+shuffle only where it pays: arrays above 16 kB

#: unit suffixes of field names, longest first (``_n_s_per_m`` before ``_per_m`` before ``_m``)
_UNIT_SUFFIXES = sorted([
    ("_per_s", "1/s"), ("_kg_per_m", "kg/m"), ("_per_m", "1/m"),
    ("_n_s_per_m", "N s/m"), ("_n_m_s", "N m s"), ("_n_per_m", "N/m"), ("_kg_m2", "kg m^2"), ("_kg_m", "kg m"),
    ("_rad_s", "rad/s"), ("_m_s", "m/s"), ("_hz", "Hz"), ("_rpm", "rpm"), ("_kg", "kg"), ("_rad", "rad"),
    ("_deg", "deg"), ("_mm", "mm"), ("_pa", "Pa"), ("_mpa", "MPa"), ("_n_m", "N m"), ("_w", "W"), ("_kw", "kW"),
    ("_n", "N"), ("_m", "m"), ("_s", "s"),
], key=lambda item: -len(item[0]))


#: Units of names that carry no unit suffix (the toolkit's conventions; "1" = dimensionless).
_NAMED_UNITS = {
    "modal_constant": "1/kg",  # receptance modal constant, whatever the FRF kind
    "damping_ratio": "1", "chi2": "1", "quality": "1", "mpc": "1", "lines_per_bandwidth": "1",
    "mode_shape": "1", "participation": "1", "coherence": "1", "multiple_coherence": "1",
    "rtol": "1", "atol": "1", "settle_tolerance": "1", "balance_fraction": "1", "reduction": "1",
    "efficiency": "1", "slip": "1", "fraction": "1", "mac": "1", "order": "1", "orders": "1", "harmonics": "1",
}


def units_of(name: str) -> str | None:
    """Unit implied by a field name (``stiffness_n_per_m`` → ``N/m``, ``damping_ratio`` → ``1``), or None.

    Suffixes first (longest first), then the names of :data:`_NAMED_UNITS`, then
    counts (``n_…``) and ratios (``…_ratio``), which are dimensionless.
    """
    lower = name.lower()
    if lower in _NAMED_UNITS:
        return _NAMED_UNITS[lower]
    for suffix, unit in _UNIT_SUFFIXES:
        if lower.endswith(suffix):
            return unit
    if lower.startswith("n_") or lower.endswith(("_ratio", "_fraction", "_count")):
        return "1"
    return None


@dataclass(frozen=True)
class Archive:
    """Content of an archive file."""

    items: dict[str, Any]
    attrs: dict[str, str]
    scene_text: str | None = None
    inputs_hash: dict[str, str] = field(default_factory=dict)
    #: item name → the warnings given while it was computed (items written with some)
    warnings: dict[str, tuple[str, ...]] = field(default_factory=dict)

    def __getitem__(self, name: str) -> Any:
        return self.items[name]


def _set_units(node, name: str, unit: str | None = None) -> None:
    """``units`` attribute: the explicit unit, else the name's, else "1" for integers and booleans
    (counts, indices, orders, flags)."""
    unit = (unit if isinstance(unit, str) else None) or units_of(name)
    if unit is None and node.dtype.kind in "biu":
        unit = "1"
    if unit is not None:
        node.attrs["units"] = unit


def write_node(parent: h5py.Group, name: str, obj: Any, unit: str | None = None) -> None:
    """Write ``obj`` as child ``name`` of ``parent`` (recursively).

    ``unit`` overrides the unit derived from the name (a dataclass's ``archive_units()``);
    the items of a tuple, list or dict take the unit of the container (or of their key). A dict as
    ``unit`` holds the units of a dataclass's fields that its container knows and it does not (the
    modal constants of a result whose FRF was in V/V): it goes to the dataclass, or to each dataclass
    of a tuple or list.
    """
    from .frf import FRF

    if isinstance(obj, FRF):
        group = parent.create_group(name)
        write_frf_group(group, obj)
        group.attrs["__type__"] = "frf"
        return
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        group = parent.create_group(name)
        cls = type(obj)
        group.attrs["__type__"] = "dataclass"
        group.attrs["__class__"] = f"{cls.__module__}:{cls.__qualname__}"
        explicit = obj.archive_units() if callable(getattr(obj, "archive_units", None)) else {}
        if isinstance(unit, dict):  # what the container knows of this dataclass's units comes first
            explicit = {**explicit, **unit}
        for f in dataclasses.fields(obj):
            write_node(group, f.name, getattr(obj, f.name), unit=explicit.get(f.name))
            if isinstance(explicit.get(f.name), str) and isinstance(group[f.name], h5py.Dataset):
                group[f.name].attrs["units"] = explicit[f.name]  # units the field name cannot say
        return
    if obj is None:
        parent.create_group(name).attrs["__type__"] = "none"
        return
    if isinstance(obj, (bool, np.bool_)):
        ds = parent.create_dataset(name, data=np.bool_(obj))
        ds.attrs["__type__"] = "bool"
        ds.attrs["units"] = "1"
        return
    if isinstance(obj, (int, float, complex)) and not isinstance(obj, np.generic):
        kind = type(obj).__name__
        ds = parent.create_dataset(name, data=obj)
        ds.attrs["__type__"] = kind
        _set_units(ds, name, unit)
        return
    if isinstance(obj, np.generic):
        ds = parent.create_dataset(name, data=obj)
        ds.attrs["__type__"] = "npscalar"
        _set_units(ds, name, unit)
        return
    if isinstance(obj, str):
        ds = parent.create_dataset(name, data=obj, dtype=h5py.string_dtype())
        ds.attrs["__type__"] = "str"
        return
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "US":
            ds = parent.create_dataset(name, data=obj.astype(object), dtype=h5py.string_dtype())
            ds.attrs["__type__"] = "str_array"
            return
        if obj.dtype.kind == "O":
            raise ArchiveError(f"archive: field '{name}' is an object array; expected numbers or strings")
        kwargs = {}
        if obj.nbytes > _COMPRESS_BYTES and obj.ndim >= 1:
            kwargs = {"compression": "gzip", "compression_opts": 4, "shuffle": True}
        ds = parent.create_dataset(name, data=obj, **kwargs)
        ds.attrs["__type__"] = "ndarray"
        _set_units(ds, name, unit)
        return
    if isinstance(obj, (tuple, list)):
        group = parent.create_group(name)
        group.attrs["__type__"] = type(obj).__name__
        group.attrs["__len__"] = len(obj)
        for i, item in enumerate(obj):
            write_node(group, str(i), item, unit=unit or units_of(name))
        return
    if isinstance(obj, dict):
        group = parent.create_group(name)
        group.attrs["__type__"] = "dict"
        for i, (key, item) in enumerate(obj.items()):
            if not isinstance(key, str):
                raise ArchiveError(f"archive: dict '{name}' has a key of type {type(key).__name__}; expected str")
            write_node(group, f"k{i}", item, unit=units_of(key))
            group[f"k{i}"].attrs["__key__"] = key
        return
    raise ArchiveError(f"archive: cannot store field '{name}' of type {type(obj).__name__}")


#: classes that moved: the ``@__class__`` an older archive names -> where the class lives now.
#: Archives keep loading after a class moves; add a line here when one does.
RENAMED_CLASSES: dict[str, str] = {
    # the band-wise algorithms moved into the modal.sdof package
    "modal.halfpower:HalfPowerEstimate": "modal.sdof.halfpower:HalfPowerEstimate",
    "modal.circlefit:CircleEstimate": "modal.sdof.circlefit:CircleEstimate",
    "modal.checks:MissingMode": "modal.sdof.checks:MissingMode",
    # balancer laid out one package per study: crank and mounts under compressor/, shaft and the
    # report under drive/ (the belt module, once balancer/drive.py, is balancer/drive/belt.py)
    "balancer.crank.model:SliderCrank": "balancer.compressor.crank.model:SliderCrank",
    "balancer.crank.model:RodSplit": "balancer.compressor.crank.model:RodSplit",
    "balancer.crank.forces:ShakingForce": "balancer.compressor.crank.forces:ShakingForce",
    "balancer.crank.forces:ShakingHarmonics": "balancer.compressor.crank.forces:ShakingHarmonics",
    "balancer.crank.counterweight:CounterweightEvaluation": "balancer.compressor.crank.counterweight:CounterweightEvaluation",
    "balancer.crank.counterweight:OptimalCurve": "balancer.compressor.crank.counterweight:OptimalCurve",
    "balancer.crank.counterweight:OptimalCounterweight": "balancer.compressor.crank.counterweight:OptimalCounterweight",
    "balancer.crank.counterweight:Counterweight": "balancer.compressor.crank.counterweight:Counterweight",
    "balancer.crank.counterweight:GridSearchResult": "balancer.compressor.crank.counterweight:GridSearchResult",
    "balancer.mounts:RigidBody": "balancer.compressor.mounts:RigidBody",
    "balancer.mounts:Mount": "balancer.compressor.mounts:Mount",
    "balancer.mounts:MountedBody": "balancer.compressor.mounts:MountedBody",
    "balancer.mounts:MountModes": "balancer.compressor.mounts:MountModes",
    "balancer.mounts:HarmonicResponse": "balancer.compressor.mounts:HarmonicResponse",
    "balancer.mounts:BalancingComparison": "balancer.compressor.mounts:BalancingComparison",
    "balancer.shaft.statics:PointLoad": "balancer.drive.shaft.statics:PointLoad",
    "balancer.shaft.statics:ShaftGeometry": "balancer.drive.shaft.statics:ShaftGeometry",
    "balancer.shaft.statics:ShaftAnalysis": "balancer.drive.shaft.statics:ShaftAnalysis",
    "balancer.shaft.statics:ShaftDiagram": "balancer.drive.shaft.statics:ShaftDiagram",
    "balancer.shaft.sizing:ShaftSizing": "balancer.drive.shaft.sizing:ShaftSizing",
    "balancer.shaft.stiffness:CriticalSpeed": "balancer.drive.shaft.stiffness:CriticalSpeed",
    "balancer.shaft.stiffness:SpeedMargin": "balancer.drive.shaft.stiffness:SpeedMargin",
    "balancer.shaft.handover:RotorHandover": "balancer.drive.shaft.handover:RotorHandover",
    "balancer.drive:CorrectionTable": "balancer.drive.belt:CorrectionTable",
    "balancer.drive:BeltStage": "balancer.drive.belt:BeltStage",
    "balancer.drive:BeltStageSpec": "balancer.drive.belt:BeltStageSpec",
    "balancer.drive:BeltDrive": "balancer.drive.belt:BeltDrive",
    "balancer.drive_report:ReportRow": "balancer.drive.report:ReportRow",
}


def _class_from(path: str):
    path = RENAMED_CLASSES.get(path, path)
    module_name, _, qualname = path.partition(":")
    if not module_name.startswith(_ALLOWED_MODULES):
        raise ArchiveError(f"archive names class {path!r}; only classes of modal and balancer are rebuilt")
    try:
        obj = importlib.import_module(module_name)
        for part in qualname.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError):
        raise ArchiveError(f"archive names class {path!r}, which this version of the toolkit does not have") from None
    return obj


def _name_units(name: str) -> tuple[str, ...]:
    """The units a field's name says by its suffixes (``mass_kg`` → kg), longest suffix first; empty for no
    suffix, or for a name whose unit is a convention that a result may override (``modal_constant`` in V/V).
    Every suffix the name ends with counts: the label an earlier version derived from a shorter suffix (``m`` for
    ``..._kg_per_m``) is one of them, never a unit of another scale (g for ``_kg``)."""
    lower = name.lower()
    if lower in _NAMED_UNITS:
        return ()
    return tuple(unit for suffix, unit in _UNIT_SUFFIXES if lower.endswith(suffix))


def _check_units(group, obj, children=None, kinds=None) -> None:
    """Refuse a dataclass's number stored without the unit :func:`write_node` gives it (the class's
    ``archive_units()``, else the unit its name's suffix says, as ``kg`` for ``mass_kg``): an archive of another
    tool under the same names, or one edited by hand, would be read in the wrong unit. A field named with a unit
    suffix must carry it; one whose unit the class gives may carry none (archives of earlier versions).
    ``children``, ``kinds``: the group's members by name, as the reader already opened them, and their types."""
    explicit = obj.archive_units() if callable(getattr(obj, "archive_units", None)) else {}
    for name, node in (group.items() if children is None else children.items()):
        kind = _str_type(node) if kinds is None else kinds[name]
        if not isinstance(node, h5py.Dataset) or kind not in _NUMBER_TYPES:
            continue
        unit = _text_attr(node, "units")
        unit = unit.decode() if isinstance(unit, bytes) else unit
        if isinstance(explicit.get(name), str):  # a unit the name cannot say: earlier versions wrote none
            expected = (explicit[name], *_name_units(name)) if unit is not None else ()
        else:
            expected = _name_units(name)
        if expected and unit not in expected:
            said = "no units attribute" if unit is None else f"units {str(unit)!r}"
            raise ArchiveError(f"{node.file.filename}: {node.name} has {said}; expected {expected[0]!r} (an archive "
                               "of another tool, or edited?): the toolkit reads numbers only in the units it wrote "
                               "them in")


_NUMBER_TYPES = ("int", "float", "complex", "npscalar", "ndarray")
_TEXT = h5py.string_dtype()


def _text_attr(node, name: str):
    """``node.attrs.get(name)`` (a missing attribute: None), read by h5py's low-level calls where it is one
    variable-length string, as :func:`write_node` writes them: ``attrs.get`` builds the attribute's memory type
    and its NumPy type afresh on every read (two thirds of a small archive's reading time went to attributes)."""
    try:
        attr = h5py.h5a.open(node.id, name.encode())
    except KeyError:
        return None
    stored = attr.get_type()
    if not (isinstance(stored, h5py.h5t.TypeStringID) and stored.is_variable_str()
            and stored.get_cset() == h5py.h5t.CSET_UTF8 and attr.shape == ()):
        return node.attrs.get(name)
    value = np.zeros((), dtype=_TEXT)
    attr.read(value, mtype=_TEXT_TYPE)
    value = value[()]
    return value.decode("utf-8", "surrogateescape") if isinstance(value, bytes) else value


_TEXT_TYPE = h5py.h5t.py_create(_TEXT)


def _str_type(node) -> str | None:
    kind = _text_attr(node, "__type__")
    return kind.decode() if isinstance(kind, bytes) else kind


def _check_number(node, kind: str) -> None:
    """Refuse a number node whose data is not what its ``__type__`` says: text, or an array for one number."""
    if not isinstance(node, h5py.Dataset) or node.dtype.kind not in "biufc":
        what = "a group" if not isinstance(node, h5py.Dataset) else f"data of type {node.dtype}"
        raise ArchiveError(f"{node.file.filename}: {node.name} holds {what}; expected numbers (an archive of another "
                           "tool, or edited?)")
    if kind != "ndarray" and node.shape != ():
        raise ArchiveError(f"{node.file.filename}: {node.name} holds an array of shape {node.shape}; expected one "
                           "number (an archive of another tool, or edited?)")


def read_node(node, kind: str | None = None) -> Any:
    """Rebuild the Python object stored at an HDF5 node by :func:`write_node` (``kind``: its ``__type__``, when
    the caller has read it).

    Raises
    ------
    ArchiveError
        A result's number stored with another unit than the one the toolkit writes, or with none
        (:func:`_check_units`).
    """
    kind = _str_type(node) if kind is None else kind
    if kind == "frf":
        return read_frf_group(node, source=node.file.filename)
    if kind == "dataclass":
        stored_class = _text_attr(node, "__class__")
        cls = _class_from(str(node.attrs["__class__"] if stored_class is None else stored_class))
        children = {name: node[name] for name in node.keys()}
        kinds = {name: _str_type(child) for name, child in children.items()}
        values = {name: read_node(child, kinds[name]) for name, child in children.items()}
        init = {f.name: values[f.name] for f in dataclasses.fields(cls) if f.init and f.name in values}
        missing = [f.name for f in dataclasses.fields(cls) if f.init and f.name not in values
                   and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
        if missing:
            raise ArchiveError(f"{node.file.filename}: {node.name} ({cls.__name__}) has no field {', '.join(missing)}; "
                               "expected every field the toolkit writes (an archive of another tool, or edited?)")
        try:
            obj = cls(**init)
        except (TypeError, ValueError) as exc:
            raise ArchiveError(f"{node.file.filename}: {node.name} ({cls.__name__}) cannot be rebuilt from its fields "
                               f"({' '.join(str(exc).split())}); expected an archive written by the toolkit") from None
        for f in dataclasses.fields(cls):
            if not f.init and f.name in values:
                object.__setattr__(obj, f.name, values[f.name])
        _check_units(node, obj, children, kinds)
        return obj
    if kind == "none":
        return None
    if kind in ("bool",):
        return bool(node[()])
    if kind in _NUMBER_TYPES:
        _check_number(node, kind)
    if kind in ("int", "float", "complex"):
        return {"int": int, "float": float, "complex": complex}[kind](node[()])
    if kind == "npscalar":
        return node[()]
    if kind == "str":
        value = node[()]
        return value.decode() if isinstance(value, bytes) else str(value)
    if kind == "str_array":
        return np.array([v.decode() if isinstance(v, bytes) else v for v in node[()].ravel()]).reshape(node.shape)
    if kind == "ndarray":
        return node[()]
    if kind in ("tuple", "list"):
        items = [read_node(node[str(i)]) for i in range(int(node.attrs["__len__"]))]
        return tuple(items) if kind == "tuple" else items
    if kind == "dict":
        children = sorted(node.keys(), key=lambda k: int(k[1:]))
        return {str(node[c].attrs["__key__"]): read_node(node[c]) for c in children}
    raise ArchiveError(f"{node.file.filename}: node {node.name} has unknown type {kind!r}")


def write_archive(path: str | os.PathLike, items: dict[str, Any], scene_text: str | None = None,
                  inputs_hash: dict[str, str] | None = None, created: str | None = None,
                  warnings: dict[str, Sequence[str]] | None = None) -> Path:
    """Write result objects to an HDF5 archive, crash-safely.

    Parameters
    ----------
    path : path-like
        Target file; replaced atomically.
    items : dict
        Top-level name → result (dataclass, FRF, array, number, string, …).
    scene_text : str, optional
        Scene file text, stored verbatim under ``/scene``.
    inputs_hash : dict, optional
        Stage name → hash of its inputs, stored as ``@inputs_hash``.
    created : str, optional
        ISO 8601 creation time; default now (UTC, ``YYYY-MM-DDTHH:MM:SSZ``).
    warnings : dict, optional
        Item name → the warnings given while it was computed, stored as the item's ``@warnings`` (read back by
        :func:`read_warnings`).
    """
    from .io._atomic import atomic_path

    path = Path(path)
    hashes = inputs_hash or {}

    def verify(tmp: Path) -> None:
        with h5py.File(tmp, "r") as f:
            check_schema(f, str(path), error=ArchiveError)
            missing = [name for name in items if name not in f]
            if missing:
                raise ArchiveError(f"{path}: verification after writing found no group {missing[0]!r}")

    with atomic_path(path, verify=verify) as tmp:
        with h5py.File(tmp, "w", track_order=True) as f:
            write_root_attrs(f, created)
            if scene_text is not None:
                f.create_dataset("scene", data=scene_text, dtype=h5py.string_dtype())
            for name, obj in items.items():
                if name == "scene":
                    raise ArchiveError("archive: item name 'scene' is reserved for the scene text")
                write_node(f, name, obj)
                if name in hashes:
                    f[name].attrs["inputs_hash"] = hashes[name]
                if warnings and warnings.get(name):
                    f[name].attrs["warnings"] = np.array(list(warnings[name]), dtype=h5py.string_dtype())
    return path


def read_warnings(node) -> tuple[str, ...]:
    """The warnings archived with an item by :func:`write_archive` (none for an item written without)."""
    said = node.attrs.get("warnings")
    if said is None:
        return ()
    return tuple(v.decode() if isinstance(v, bytes) else str(v) for v in np.atleast_1d(said))


def read_archive(path: str | os.PathLike) -> Archive:
    """Read an archive written by :func:`write_archive` back into the same objects."""
    src = str(path)
    if not Path(path).is_file():
        raise ArchiveError(f"{src}: no such archive file")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise ArchiveError(f"{src}: not a readable HDF5 file ({' '.join(str(exc).split())}); expected an archive "
                           "of python -m modal fit --archive or python -m balancer run") from None
    with f:
        check_schema(f, src, error=ArchiveError)
        frfs = f.get("frf")
        if isinstance(frfs, h5py.Group) and "__type__" not in frfs.attrs:  # /frf/<name>: modal.io.write_frf's layout
            raise ArchiveError(f"{src}: an FRF file (/frf/<name>, as modal frf --out writes it), not an archive of "
                               f"results; expected an archive of a fit: python -m modal fit {src} --archive OUT.h5")
        attrs = {k: str(v) for k, v in f.attrs.items()}
        scene = None
        if "scene" in f:
            value = f["scene"][()]
            scene = value.decode() if isinstance(value, bytes) else str(value)
        items, hashes, said = {}, {}, {}
        for name in f.keys():
            if name == "scene":
                continue
            items[name] = read_node(f[name])
            if "inputs_hash" in f[name].attrs:
                hashes[name] = str(f[name].attrs["inputs_hash"])
            warned = read_warnings(f[name])
            if warned:
                said[name] = warned
    return Archive(items=items, attrs=attrs, scene_text=scene, inputs_hash=hashes, warnings=said)

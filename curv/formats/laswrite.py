"""Writing LAS/LAZ: every record of the input kept as it is, the curvature added as extra bytes.

The output is the input file with more bytes per point record: the same point format, version,
scales and offsets, the same VLRs (the coordinate system's among them) and EVLRs, every standard
dimension and the file's own extra bytes byte for byte, in the input's order; the estimate goes
into LAS 1.4 extra bytes (an Extra Bytes VLR describes them, so laspy, PDAL and CloudCompare read
them by name). :data:`FIELDS` names them; ``groups`` choose which are written:

================  ========  =============================================================
name              type      meaning
================  ========  =============================================================
k1, k2            float32   principal curvatures (1 / the file's unit), k1 >= k2
mean, gaussian    float32   H = (k1 + k2) / 2, K = k1 k2
valid             uint8     1 where the estimate is trustworthy, 0 elsewhere
reason            uint8     :class:`curv.Reason` code (0 OK, 1 BORDER, ... 8 ORIENTATION)
d1x .. d2z        float32   unit principal directions (group ``directions``)
k1_se, k2_se      float32   standard errors of k1, k2 (group ``errors``)
nx, ny, nz        float32   the unit normal the estimate used (group ``normals``)
================  ========  =============================================================

Values where ``valid`` is 0 are NaN. The header's statistics (bounds, counts by return, GPS
time range) are those of the records, as laspy recomputes them while writing. Two kinds of VLR
cannot stay true in a file written anew and are left out: LASzip's (the writer makes its own)
and COPC's (its index points into the input's compressed chunks; the output is a plain LAZ).
An input that already has a dimension of one of these names with the same type (a file curvlab
wrote) has its values replaced; with another type it is refused.

The output is written atomically (:func:`curv.formats.atomic.atomic_path`): a truncated input,
a full disk or an interrupt leaves no partial file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Generator, Mapping

import numpy as np

from ..core.errors import LoadError
from ..core.paths import check_readable, one_line
from ..core.quantities import compute
from .atomic import atomic_path

__all__ = ["LasField", "FIELDS", "GROUPS", "fields_for", "iter_write_las", "write_las", "save_las",
           "curvature_columns", "LAS_SUFFIXES", "CHUNK_POINTS"]

LAS_SUFFIXES = (".las", ".laz")

CHUNK_POINTS = 1 << 19
"""Records read, extended and written at a time (about 50 MB of records in and out)."""

_LAS_HINT = "pip install 'curvlab[points]'"


@dataclass(frozen=True)
class LasField:
    """One extra-bytes dimension of the output.

    Attributes
    ----------
    name, dtype, description : str
        The dimension as the Extra Bytes VLR declares it (description at most 32 characters).
    source : str
        The result column it comes from (``k1``, ``d1``, ``normals``, ...; ``mean`` and
        ``gaussian`` are computed from k1 and k2 by :mod:`curv.core.quantities`).
    component : int or None
        The column of an (m, 3) source.
    group : str
        ``curvature`` (always written), ``directions``, ``errors`` or ``normals``.
    """

    name: str
    dtype: str
    description: str
    source: str
    component: int | None = None
    group: str = "curvature"


def _vector(prefix: str, source: str, what: str, group: str) -> tuple:
    return tuple(LasField(f"{prefix}{c}", "f4", f"{what}, {c}", source, i, group) for i, c in enumerate("xyz"))


FIELDS: tuple[LasField, ...] = (
    LasField("k1", "f4", "larger principal curvature", "k1"),
    LasField("k2", "f4", "smaller principal curvature", "k2"),
    LasField("mean", "f4", "mean curvature (k1 + k2) / 2", "mean"),
    LasField("gaussian", "f4", "Gaussian curvature k1 k2", "gaussian"),
    LasField("valid", "u1", "1: valid estimate, 0: see reason", "valid"),
    LasField("reason", "u1", "curvlab reason code, 0 OK", "reason"),
    *_vector("d1", "d1", "direction of k1", "directions"),
    *_vector("d2", "d2", "direction of k2", "directions"),
    LasField("k1_se", "f4", "standard error of k1", "k1_se", group="errors"),
    LasField("k2_se", "f4", "standard error of k2", "k2_se", group="errors"),
    *_vector("n", "normals", "normal used", "normals"),
)
"""Every extra dimension curvlab can write, in the order it writes them."""

GROUPS = ("directions", "errors", "normals")
"""The optional groups of :data:`FIELDS` (``curvature`` is always written)."""


def fields_for(groups=()) -> tuple[LasField, ...]:
    """The fields of the ``curvature`` group and of ``groups`` (a subset of :data:`GROUPS`)."""
    groups = tuple(groups)
    unknown = [g for g in groups if g not in GROUPS]
    if unknown:
        raise ValueError(f"unknown LAS extra-bytes group {unknown[0]!r}; choose from {', '.join(GROUPS)}")
    return tuple(f for f in FIELDS if f.group == "curvature" or f.group in groups)


def curvature_columns(result, start: int = 0, stop: int | None = None) -> dict:
    """The result columns a writer reads (``k1``, ``k2``, ``d1``, ``d2``, ``normals``, ``valid``,
    ``reason``, ``k1_se``, ``k2_se``) of rows ``start:stop`` of a :class:`curv.Curvature`."""
    names = ("k1", "k2", "d1", "d2", "normals", "valid", "reason", "k1_se", "k2_se")
    return {name: getattr(result, name)[start:stop] for name in names}


def _values(field: LasField, columns: Mapping[str, np.ndarray]) -> np.ndarray:
    if field.source in ("mean", "gaussian"):
        return compute(field.source, columns["k1"], columns["k2"])
    values = np.asarray(columns[field.source])
    return values if field.component is None else values[:, field.component]


def _is_copc(vlr) -> bool:
    return getattr(vlr, "user_id", "").rstrip("\0") == "copc"


def _output_header(header, fields: tuple[LasField, ...], path: Path):
    """The input's header with ``fields`` added as extra bytes (those it has with the same type reused)."""
    import copy

    import laspy
    from laspy.vlrs.vlrlist import VLRList

    # the input header as it is (the writer recomputes the counts, bounds and LASzip's VLR)
    out = copy.deepcopy(header)
    out.vlrs = VLRList([v for v in header.vlrs if not _is_copc(v)])
    have = {d.name: d for d in header.point_format.extra_dimensions}
    new = []
    for f in fields:
        if f.name in have:
            kept = np.dtype(have[f.name].dtype)
            if kept != np.dtype(f.dtype) or have[f.name].num_elements != 1:
                raise LoadError(f"{path}: has an extra dimension {f.name!r} of type {kept}; curvlab writes "
                                f"{f.name} as {np.dtype(f.dtype)} (rename that dimension first)")
        elif f.name in header.point_format.dimension_names:
            raise LoadError(f"{path}: its point format has a standard dimension named {f.name!r}, which curvlab "
                            f"would write as an extra byte")
        else:
            new.append(laspy.ExtraBytesParams(name=f.name, type=f.dtype, description=f.description))
    if new:
        out.add_extra_dims(new)
    return out


def _open_input(path: Path):
    try:
        import laspy
    except ImportError:
        raise LoadError(f"{path}: LAS/LAZ needs laspy ({_LAS_HINT})") from None
    check_readable(path)
    from .lasheader import check_las_header

    check_las_header(path)  # the header's promises against the file, before laspy reads it
    try:
        return laspy.open(path)
    except Exception as exc:  # noqa: BLE001 - laspy's and lazrs's errors become one line
        raise LoadError(f"{path}: not a readable {path.suffix.lstrip('.').upper()} file ({one_line(exc)})") from None


def iter_write_las(path, source, values: Callable[[int, int], Mapping[str, np.ndarray]], *, groups=(),
                   chunk: int = CHUNK_POINTS, compress: bool | None = None) -> Generator[float, None, Path]:
    """Write ``source``'s records with the estimate added (module notes), a chunk at a time: a
    generator yielding the fraction written, returning the output path.

    Parameters
    ----------
    path : str or Path
        The output, ``.las`` or ``.laz`` (compressed unless ``compress`` says otherwise).
    source : str or Path
        The LAS/LAZ file the estimate was made on; its records are read again, in order.
    values : callable
        ``values(start, stop)`` returns the result columns (:func:`curvature_columns`' keys) of
        records ``start:stop``; called once per chunk, in order.
    groups : sequence of str
        Optional field groups (:data:`GROUPS`).
    chunk : int
        Records per chunk.
    compress : bool, optional
        LAZ or LAS; default by ``path``'s suffix.

    Raises
    ------
    LoadError
        ``source`` unreadable, truncated or holding fewer records than its header says, or a name
        clash (module notes): one line naming the file. No output is left behind.
    OSError
        The output cannot be written (a full disk): no output is left behind either.
    """
    import laspy
    from laspy.vlrs.vlrlist import VLRList

    path, source = Path(path), Path(source)
    fields = fields_for(groups)
    compress = path.suffix.lower() == ".laz" if compress is None else bool(compress)
    with _open_input(source) as reader:
        header = reader.header
        total = int(header.point_count)
        out_header = _output_header(header, fields, source)
        old_size = header.point_format.size
        new_size = out_header.point_format.size
        evlrs = [e for e in (reader.evlrs or []) if not _is_copc(e)]
        with atomic_path(path) as tmp:
            with laspy.open(tmp, mode="w", header=out_header, do_compress=compress) as writer:
                done = 0
                try:
                    for points in reader.chunk_iterator(chunk):
                        m = len(points)
                        if m == 0:
                            break
                        record = laspy.ScaleAwarePointRecord.zeros(m, header=writer.header)
                        # every byte of the input records as it is; the added dimensions after them
                        record.array.view(np.uint8).reshape(m, new_size)[:, :old_size] = \
                            points.array.view(np.uint8).reshape(m, old_size)
                        columns = values(done, done + m)
                        for f in fields:
                            record.array[f.name] = _values(f, columns)
                        writer.write_points(record)
                        done += m
                        yield done / max(total, 1)
                except LoadError:
                    raise
                except OSError:
                    raise
                except Exception as exc:  # noqa: BLE001 - a truncated or corrupt input, in one line
                    raise LoadError(f"{source}: record {done} and after cannot be read ({one_line(exc)})") from None
                if done != total:
                    raise LoadError(f"{source}: holds {done} point records but its header says {total}")
                if evlrs:
                    writer.write_evlrs(VLRList(evlrs))
    yield 1.0
    return path


def write_las(path, source, values, **keywords) -> Path:
    """:func:`iter_write_las` to the end."""
    gen = iter_write_las(path, source, values, **keywords)
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value


def save_las(path, source, curvature, *, groups=(), compress: bool | None = None) -> Path:
    """Write ``source`` (a LAS/LAZ file) with ``curvature`` (a :class:`curv.Curvature` of its points,
    in the file's order) added as extra bytes (module notes).

    Parameters
    ----------
    path : str or Path
        ``.las`` or ``.laz``.
    source : str or Path
        The file the points came from (:func:`curv.load`).
    curvature : Curvature
        One row per record of ``source``.
    groups : sequence of str
        Optional field groups: ``directions``, ``errors``, ``normals``.
    """
    n = curvature.k1.shape[0]
    with _open_input(Path(source)) as reader:
        count = int(reader.header.point_count)
    if count != n:
        raise ValueError(f"{source}: holds {count} points but the estimate has {n} rows")
    return write_las(path, source, lambda a, b: curvature_columns(curvature, a, b), groups=groups,
                     compress=compress)

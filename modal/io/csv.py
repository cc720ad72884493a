"""FRFs in delimited text: the common layouts, and a canonical CSV that round-trips exactly.

Reading (:func:`read_frf_csv`) accepts

* frequency + real + imaginary (``layout="re_im"``),
* frequency + magnitude + phase in degrees (``"mag_deg"``) or radians (``"mag_rad"``),
* frequency + magnitude in dB (20 log10 |H|) + phase in degrees (``"db_deg"``),
* Python/NumPy complex text, ``(a+bj)``, one column per channel, with or without a
  frequency column (``"complex"``),

with several channels as repeated column groups, optional header line(s) (which
may name the layout and the frequency unit), ``#`` comment lines, comma,
semicolon, tab or whitespace delimiters and a decimal comma (``decimal=","``).
The layout is taken from the ``layout=`` hint, the header or complex text; a
headerless file of real columns is ambiguous and must be given ``layout=``.

The canonical CSV written by :func:`write_frf_csv`::

    # format: modalbal-frf-csv 1
    # kind: accelerance
    # units: m/s^2/N
    # frequency_unit: Hz
    # channels: 2
    # response_points: ["101+Z", "102+Z"]
    # reference_points: ["1+Z", "1+Z"]
    frequency_hz,re_0,im_0,re_1,im_1
    1.0,-0.25,0.0125,...

Floats are written with :func:`repr` (shortest text that reads back to the same
double), so a write–read round trip is bit-exact. Point lines are JSON lists
and are left out when the FRF has no point ids.
"""
from __future__ import annotations

import io
import json
import os
import re
from typing import Any

import numpy as np

from ..errors import FormatError, QualityWarning, warn
from ..frf import FRF
from ._atomic import atomic_path
from ._common import (
    build_frf, check_file, frequency_factor, frequency_unit_from_text, hint_frequency_axis,
    normalise_kind, refuse_cut_last_value, resolve_kind, source_name,
)

__all__ = ["read_frf_csv", "write_frf_csv", "LAYOUTS", "CANONICAL_FORMAT"]

CANONICAL_FORMAT = "modalbal-frf-csv"
CANONICAL_MAJOR = 1
#: a phase column in degrees over at least this many lines that stays within ±π is taken for radians (warning)
_PHASE_CHECK_LINES = 20
LAYOUTS = ("re_im", "mag_deg", "mag_rad", "db_deg", "db_rad", "complex")
_LAYOUT_ALIASES = {
    "re_im": "re_im", "real_imag": "re_im", "reim": "re_im",
    "mag_deg": "mag_deg", "mag_phase_deg": "mag_deg", "mag_phase": "mag_deg",
    "mag_rad": "mag_rad", "mag_phase_rad": "mag_rad",
    "db_deg": "db_deg", "db_phase_deg": "db_deg", "db": "db_deg", "db_rad": "db_rad",
    "complex": "complex",
}
_DELIMITERS = {",": ",", ";": ";", "\t": "\t", "tab": "\t", "\\t": "\t", " ": None, "whitespace": None}


# ----------------------------------------------------------------- writing
def write_frf_csv(frf: FRF, path: str | os.PathLike) -> None:
    """Write ``frf`` as canonical CSV (bit-exact round trip), atomically.

    Parameters
    ----------
    frf : FRF
    path : path-like
        Target file; written to a temporary file beside it and renamed.
    """
    h = frf.channels
    n_ch = h.shape[0]
    lines = [
        f"# format: {CANONICAL_FORMAT} {CANONICAL_MAJOR}",
        f"# kind: {frf.kind}",
        f"# units: {frf.units}",
        "# frequency_unit: Hz",
        f"# channels: {n_ch}",
    ]
    if frf.response_points is not None:
        lines.append(f"# response_points: {json.dumps(list(frf.response_points))}")
    if frf.reference_points is not None:
        lines.append(f"# reference_points: {json.dumps(list(frf.reference_points))}")
    lines.append(",".join(["frequency_hz"] + [f"{p}_{i}" for i in range(n_ch) for p in ("re", "im")]))
    table = np.empty((frf.n_freq, 1 + 2 * n_ch))
    table[:, 0] = frf.frequency_hz
    table[:, 1::2] = h.real.T
    table[:, 2::2] = h.imag.T
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
            fh.write("\n".join(lines))
            fh.write("\n")
            fh.writelines(",".join(map(repr, row)) + "\n" for row in table.tolist())


# ----------------------------------------------------------------- reading
def read_frf_csv(path: str | os.PathLike, **hints: Any) -> FRF:
    """Read an FRF from delimited text (see the module docstring for the layouts).

    Parameters
    ----------
    path : path-like
    **hints
        ``kind`` (required unless the file's ``# kind:`` line says it),
        ``layout`` (one of :data:`LAYOUTS`), ``delimiter`` (``","``, ``";"``,
        ``"\\t"`` or ``" "`` for whitespace), ``decimal`` (``"."`` or ``","``),
        ``frequency_axis`` (unit of the frequency column: ``"hz"``, ``"rad/s"``,
        ``"cpm"``...), and for files without a frequency column ``frequency_hz``
        or ``frequency_step``/``frequency_start``; ``response_points``,
        ``reference_points``, ``units`` override the file's.

    Raises
    ------
    FormatError
        Naming the file, the line and column, and what was expected.
    FRFValidationError
        Duplicate frequency lines (unsorted ones are sorted with a ModalWarning).
    """
    src = source_name(path)
    p = check_file(path)
    raw = p.read_bytes()
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            text = raw.decode("utf-16")
        except UnicodeDecodeError:
            raise FormatError(f"{src}: line 1: damaged UTF-16 text; expected a text file of numbers") from None
        return _read_text(text, src, hints)
    if b"\x00" in raw[:4096]:
        raise FormatError(f"{src}: line 1: binary content (NUL bytes); expected a text file of numbers")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return _read_text(text, src, hints)


def _read_text(text: str, src: str, hints: dict[str, Any]) -> FRF:
    decimal = hints.get("decimal") or "."
    if decimal not in (".", ","):
        raise FormatError(f"{src}: hint decimal={decimal!r}; expected '.' or ','")
    meta: dict[str, tuple[int, str]] = {}
    header_lines: list[tuple[int, str]] = []
    data: list[tuple[int, str]] = []
    content = [(i + 1, ln.strip()) for i, ln in enumerate(text.splitlines())]
    content = [(n, ln) for n, ln in content if ln]
    if not content:
        raise FormatError(f"{src}: line 1: no content (only blank lines); expected rows of numbers")
    delim = choose_delimiter(hints, content, decimal, src)
    for n, ln in content:
        if ln.startswith("#"):
            if not data and ":" in ln:
                key, _, value = ln[1:].partition(":")
                meta[key.strip().lower()] = (n, value.strip())
            continue
        if not data and not any(_looks_numeric(tok) for tok in _split(ln, delim)):
            header_lines.append((n, ln))
            continue
        data.append((n, ln))
    if not data:
        last = header_lines[-1][0] if header_lines else content[-1][0]
        raise FormatError(f"{src}: line {last}: only a header or comments, no data lines; expected rows of numbers")
    if delim is not None and all(ln.endswith(delim) for _, ln in data):  # trailing delimiter (spreadsheets)
        data = [(n, ln[:-1]) for n, ln in data]
        header_lines = [(n, ln[:-1] if ln.endswith(delim) else ln) for n, ln in header_lines]
    canonical = _check_format(meta, src)
    names = _split(header_lines[-1][1], delim) if header_lines else None
    n_cols = len(_split(data[0][1], delim))
    if names is not None and len(names) != n_cols:
        raise FormatError(
            f"{src}: line {data[0][0]}: {n_cols} columns but the header (line {header_lines[-1][0]}) "
            f"names {len(names)}; expected the same number"
        )
    is_complex = "j" in data[0][1].lower()
    layout = _layout(hints, names, is_complex, canonical, n_cols, src, data[0][0])
    col_names = names or [f"column {k + 1}" for k in range(n_cols)]
    if not text.endswith(("\n", "\r")) and len(_split(data[-1][1], delim)) == n_cols:
        refuse_cut_last_value(text, [(n, _split(ln, delim)) for n, ln in data], col_names[-1], src)
    if layout == "complex":
        table = _parse_complex(data, delim, decimal, n_cols, col_names, src)
    else:
        table = _parse_real(data, delim, decimal, n_cols, col_names, src)
    freq_hz, resp = _to_frf_arrays(table, layout, n_cols, names, meta, hints, src)
    # kind, units and points
    file_kind = None
    where = "header"
    if "kind" in meta:
        line, value = meta["kind"]
        where = f"line {line} (field kind)"
        file_kind = normalise_kind(value, src, where)
    kind = resolve_kind(file_kind, hints, src, where,
                        why_unknown="the file has no '# kind:' line")
    n_ch = resp.shape[0]
    if "channels" in meta:
        line, value = meta["channels"]
        if value.strip() != str(n_ch):
            raise FormatError(
                f"{src}: line {line} (field channels): says {value!r} but the table holds {n_ch}; "
                "expected them to agree (file truncated or edited?)"
            )
    points = [_points(meta, key, src) for key in ("response_points", "reference_points")]
    units = meta["units"][1] if "units" in meta else None
    return build_frf(freq_hz, resp, kind, src, response_points=points[0], reference_points=points[1],
                     units=units, hints=hints)


def _check_format(meta: dict[str, tuple[int, str]], src: str) -> bool:
    if "format" not in meta:
        return False
    line, value = meta["format"]
    parts = value.split()
    if not parts or parts[0] != CANONICAL_FORMAT:
        return False
    version = parts[1] if len(parts) > 1 else "?"
    if version.split(".")[0] != str(CANONICAL_MAJOR):
        raise FormatError(
            f"{src}: line {line} (field format): {CANONICAL_FORMAT} version {version} is not supported; "
            f"expected major version {CANONICAL_MAJOR} (a newer program wrote it?)"
        )
    return True


def _points(meta: dict[str, tuple[int, str]], key: str, src: str):
    if key not in meta:
        return None
    line, value = meta[key]
    try:
        ids = json.loads(value)
    except json.JSONDecodeError:
        ids = None
    if not isinstance(ids, list):
        raise FormatError(
            f"{src}: line {line} (field {key}): {value!r} is not a JSON list; expected e.g. [\"101+Z\", \"102+Z\"]"
        )
    return tuple(str(v) for v in ids)


def choose_delimiter(hints: dict[str, Any], content: list[tuple[int, str]], decimal: str, src: str) -> str | None:
    """The delimiter a hint names, else the first of tab, ';', ',' found on each of the first five lines
    (',' not with a decimal comma); None: whitespace."""
    hint = hints.get("delimiter")
    if hint is not None:
        if hint not in _DELIMITERS:
            raise FormatError(f"{src}: hint delimiter={hint!r}; expected ',', ';', '\\t' or ' ' (whitespace)")
        delim = _DELIMITERS[hint]
        if delim == "," and decimal == ",":
            raise FormatError(f"{src}: hints delimiter=',' and decimal=',' clash; expected different characters")
        return delim
    sample = [ln for _, ln in content if not ln.startswith("#")][:5]
    for cand in ("\t", ";", ","):
        if cand == "," and decimal == ",":
            continue
        if sample and all(cand in ln for ln in sample):
            return cand
    return None


def _split(line: str, delim: str | None) -> list[str]:
    return [tok.strip() for tok in line.split(delim)] if delim else line.split()


_NUMBER_COMMA = re.compile(r"^[+-]?(\d+,?\d*|,\d+)([eE][+-]?\d+)?$")


def _looks_numeric(tok: str) -> bool:
    try:
        complex(tok.replace(" ", ""))
        return True
    except ValueError:
        return bool(_NUMBER_COMMA.match(tok))


def _layout(hints, names, is_complex, canonical, n_cols, src, first_line) -> str:
    hint = hints.get("layout")
    if hint is not None:
        key = str(hint).strip().lower()
        if key not in _LAYOUT_ALIASES:
            raise FormatError(f"{src}: hint layout={hint!r}; expected one of {', '.join(LAYOUTS)}")
        layout = _LAYOUT_ALIASES[key]
        said = _layout_from_names(names[1].lower(), names[2].lower()) if names is not None and len(names) >= 3 else None
        if said is not None and _contradicts(layout, said, names[2].lower()):
            raise FormatError(f"{src}: layout={hint!r} but the header names the columns {names[1]!r}, {names[2]!r} "
                              f"({said}); expected a layout that agrees with the header, or none")
        return layout
    if is_complex:
        return "complex"
    if canonical:
        return "re_im"
    if names is not None and len(names) >= 3:
        found = _layout_from_names(names[1].lower(), names[2].lower())
        if found:
            return found
    where = "the header does not name the columns" if names else "no header"
    raise FormatError(
        f"{src}: line {first_line}: {n_cols} real columns and {where}, so real/imaginary and "
        f"magnitude/phase cannot be told apart; expected layout= one of {', '.join(LAYOUTS)}"
    )


def _contradicts(layout: str, said: str, second: str) -> bool:
    """Whether a layout given contradicts what the header states outright: real/imaginary against
    magnitude/phase, or a phase unit the header names (a magnitude column not marked dB proves nothing)."""
    if (layout == "re_im") != (said == "re_im") or layout == "complex":
        return True
    if layout == "re_im":
        return False
    if said.startswith("db") and not layout.startswith("db"):
        return True  # the header marks the magnitude in dB
    stated = "rad" if re.search(r"rad", second) and "deg" not in second else "deg" if "deg" in second else None
    return stated is not None and not layout.endswith(stated)


def _layout_from_names(first: str, second: str) -> str | None:
    phase = re.search(r"phase|phi|arg|angle|ang\b|deg|rad", second)
    rad = bool(re.search(r"rad", second)) and "deg" not in second
    if re.search(r"^re\b|^re[_\s(\[]|real|^re$", first) and re.search(r"^im|imag", second):
        return "re_im"
    if re.search(r"db", first) and phase:
        return "db_rad" if rad else "db_deg"
    if re.search(r"mag|abs|amp|\|h\||modulus", first) and phase:
        return "mag_rad" if rad else "mag_deg"
    return None


def _number_error(src, n, col_name, tok, decimal) -> FormatError:
    if tok == "":
        what = "is empty"
    else:
        what = f"{tok!r} is not a number"
    hint = ""
    if decimal == "." and _NUMBER_COMMA.match(tok) and "," in tok:
        hint = " (decimal comma? pass decimal=',')"
    return FormatError(f"{src}: line {n}, column {col_name!r}: {what}{hint}; expected a number")


def _cut_short(line_no: int, n_tokens: int, data, n_cols: int) -> str:
    """What a message adds when the short row is the file's last: the file may be cut short."""
    return " (the last line: is the file cut short?)" if line_no == data[-1][0] and n_tokens < n_cols else ""


def _parse_real(data, delim, decimal, n_cols, col_names, src) -> np.ndarray:
    texts = [ln for _, ln in data]
    if decimal == ",":
        texts = [t.replace(",", ".") for t in texts]
    try:
        table = np.loadtxt(io.StringIO("\n".join(texts)), delimiter=delim, dtype=float, ndmin=2,
                           comments=None)
        if table.shape[1] != n_cols:
            raise ValueError
    except ValueError:
        table = None
    if table is None:  # find the first bad line for the message
        for (n, ln), t in zip(data, texts):
            toks = _split(t, delim)
            if len(toks) != n_cols:
                raise FormatError(
                    f"{src}: line {n}: {len(toks)} columns{_cut_short(n, len(toks), data, n_cols)}; expected "
                    f"{n_cols} (as on line {data[0][0]})"
                ) from None
            for k, tok in enumerate(toks):
                try:
                    float(tok)
                except ValueError:
                    orig = _split(ln, delim)[k] if decimal == "," else tok
                    raise _number_error(src, n, col_names[k], orig, decimal) from None
        raise FormatError(f"{src}: line {data[0][0]}: the table cannot be parsed; expected rows of numbers")
    _check_finite(table, data, col_names, src)
    return table


def _parse_complex(data, delim, decimal, n_cols, col_names, src) -> np.ndarray:
    table = np.empty((len(data), n_cols), dtype=complex)
    for i, (n, ln) in enumerate(data):
        toks = _split(ln, delim)
        if len(toks) != n_cols:
            raise FormatError(f"{src}: line {n}: {len(toks)} columns{_cut_short(n, len(toks), data, n_cols)}; "
                              f"expected {n_cols} (as on line {data[0][0]})")
        for k, tok in enumerate(toks):
            t = tok.replace(" ", "")
            if decimal == ",":
                t = t.replace(",", ".")
            try:
                table[i, k] = complex(t)
            except ValueError:
                raise _number_error(src, n, col_names[k], tok, decimal) from None
    _check_finite(table, data, col_names, src)
    return table


def _check_finite(table, data, col_names, src) -> None:
    bad = ~np.isfinite(table)
    if bad.any():
        i, k = (int(v) for v in np.argwhere(bad)[0])
        raise FormatError(
            f"{src}: line {data[i][0]}, column {col_names[k]!r}: value {table[i, k]} is not finite; "
            "expected a finite number"
        )


def _to_frf_arrays(table, layout, n_cols, names, meta, hints, src):
    first_line = "the first data line"
    if layout == "complex":
        if n_cols == 1:
            freq = hint_frequency_axis(hints, table.shape[0], src, "the file has no frequency column")
            return freq, table.T
        if np.any(table[:, 0].imag != 0):
            raise FormatError(
                f"{src}: column {(names or ['column 1'])[0]!r}: complex values; expected real frequencies"
            )
        freq_col, resp = table[:, 0].real, table[:, 1:].T
    else:
        if n_cols < 3 or (n_cols - 1) % 2:
            raise FormatError(
                f"{src}: {first_line}: {n_cols} columns; expected a frequency column and then one pair "
                f"of columns per channel ({layout}), i.e. an odd number >= 3"
            )
        a, b = table[:, 1::2].T, table[:, 2::2].T
        if layout == "re_im":
            resp = a + 1j * b
        else:
            if not layout.startswith("db") and np.any(a < 0):
                row, column = np.unravel_index(np.argmax(a < 0), a.shape)
                name = (repr(names[1 + 2 * row]) if names is not None and len(names) > 1 + 2 * row
                        else str(2 + 2 * row))
                raise FormatError(f"{src}: column {name}: negative magnitude {a[row, column]:g} in data row "
                                  f"{column + 1} (layout {layout}); expected magnitudes >= 0 (in dB? layout db_deg "
                                  "or db_rad)")
            mag = 10.0 ** (a / 20.0) if layout.startswith("db") else a
            if layout.endswith("deg") and b.shape[1] >= _PHASE_CHECK_LINES and 0.5 < np.max(np.abs(b)) <= np.pi + 1e-6:
                warn(f"{src}: the phase column{'s' if b.shape[0] > 1 else ''} in degrees span only "
                     f"{np.min(b):.3g} to {np.max(b):.3g} over {b.shape[1]} lines (a mode turns the phase by 180 "
                     "degrees): radians? (layout mag_rad or db_rad)", QualityWarning)
            phase = np.deg2rad(b) if layout.endswith("deg") else b
            resp = mag * np.exp(1j * phase)
        freq_col = table[:, 0]
    for key in ("frequency_hz", "frequency_step"):
        if hints.get(key) is not None:
            raise FormatError(f"{src}: the file has a frequency column; expected no {key}= hint")
    unit = hints.get("frequency_axis")
    where = "hint frequency_axis="
    if unit is None and "frequency_unit" in meta:
        line, unit = meta["frequency_unit"]
        where = f"line {line} (field frequency_unit)"
    if unit is None and names:
        unit = frequency_unit_from_text(names[0])
        where = f"header column {names[0]!r}"
    factor = 1.0 if unit is None else frequency_factor(unit, src, where)
    freq = freq_col if factor == 1.0 else freq_col * factor
    return freq, resp

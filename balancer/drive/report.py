"""Plain-text report of the drive chain (quantity, formula, value, unit) and the
plot of a shaft's shear-force and bending-moment diagrams.

The report is an edge of the toolkit, so it shows engineering units (mm, MPa,
rpm, degrees) and says which in its unit column.  Plot functions never touch
pyplot state: they draw on the Axes they are given or on a new
``matplotlib.figure.Figure`` and return the Figure.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from modal.errors import ParameterError

from .belt import BeltDrive, BeltStage
from .shaft import RotorHandover, ShaftAnalysis, ShaftSizing, shaft_diagram

__all__ = [
    "ReportRow",
    "belt_stage_rows",
    "shaft_rows",
    "sizing_rows",
    "handover_rows",
    "format_table",
    "drive_report",
    "plot_shear",
    "plot_moment",
    "plot_shaft_diagrams",
]


@dataclass(frozen=True, slots=True)
class ReportRow:
    """One line of the chain.

    Attributes
    ----------
    quantity : str
        What the value is.
    formula : str
        How it is computed.
    value : float
        The value, in ``unit``.
    unit : str
        Unit of ``value`` (engineering units for display).
    """

    quantity: str
    formula: str
    value: float
    unit: str


def belt_stage_rows(stage: BeltStage) -> tuple[ReportRow, ...]:
    """Rows of one belt stage (speeds in rpm, lengths in mm, angle in degrees).

    Parameters
    ----------
    stage : BeltStage
        Result of :func:`balancer.drive.belt_stage`.

    Returns
    -------
    tuple of ReportRow
    """
    p = f"[{stage.name}] " if stage.name else ""
    rows = [
        ReportRow(p + "driven speed", "n2 = n1 d / D", stage.driven_speed_rpm, "rpm"),
        ReportRow(p + "design power", "Pd = P * service factor", stage.design_power_w / 1e3, "kW"),
        ReportRow(p + "belt pitch length", "L = 2C + 1.57(D+d) + (D-d)^2/4C", stage.belt_length_m * 1e3, "mm"),
    ]
    if stage.standard_length_from_series:
        rows += [
            ReportRow(p + "standard belt length", "next standard >= L", stage.standard_length_m * 1e3, "mm"),
            ReportRow(p + "centre distance for it", "C from L (inverse)", stage.center_distance_for_standard_length_m * 1e3, "mm"),
        ]
    rows += [
        ReportRow(p + "arc of contact", "180 - 2 asin(|D-d|/2C)", stage.arc_of_contact_deg, "deg"),
        ReportRow(p + "belt speed", "v = pi d n1 / 60", stage.belt_speed_m_s, "m/s"),
        ReportRow(p + "effective pull", "Fe = P / v", stage.effective_pull_n, "N"),
    ]
    if stage.belt_count_basis == "rating":
        rows.append(ReportRow(p + "belts required", "z = Pd / (P1 Ktheta KL)", stage.belts_required, "-"))
    rows += [
        ReportRow(p + "belts used", f"({stage.belt_count_basis})", float(stage.belt_count), "-"),
        ReportRow(p + "shaft load", "(k1 Fe + z k2 v^2) sin(theta/2)", stage.shaft_load_n, "N"),
        ReportRow(p + "driven shaft torque", "T = P / omega2", stage.driven_torque_n_m, "N m"),
    ]
    return tuple(rows)


def shaft_rows(analysis: ShaftAnalysis) -> tuple[ReportRow, ...]:
    """Rows of a shaft analysis: reactions, largest moment, torque.

    Parameters
    ----------
    analysis : ShaftAnalysis
        Result of :func:`balancer.drive.shaft.analyse_shaft`.

    Returns
    -------
    tuple of ReportRow
    """
    return (
        ReportRow("reaction A, vertical", "sum F = 0", analysis.reaction_a_vertical_n, "N"),
        ReportRow("reaction B, vertical", "sum M_A = 0", analysis.reaction_b_vertical_n, "N"),
        ReportRow("reaction A, horizontal", "sum F = 0", analysis.reaction_a_horizontal_n, "N"),
        ReportRow("reaction B, horizontal", "sum M_A = 0", analysis.reaction_b_horizontal_n, "N"),
        ReportRow("largest bending moment", "max sqrt(Mv^2 + Mh^2)", analysis.max_moment_n_m, "N m"),
        ReportRow("  at", "station", analysis.max_moment_position_m * 1e3, "mm"),
        ReportRow("torque", "T = P / omega", analysis.torque_n_m, "N m"),
    )


def sizing_rows(sizing: ShaftSizing) -> tuple[ReportRow, ...]:
    """Rows of a shaft sizing, labelled with its method.

    Parameters
    ----------
    sizing : ShaftSizing
        Result of :func:`balancer.drive.shaft.shaft_diameter_soderberg` or
        :func:`balancer.drive.shaft.shaft_diameter_asme`.

    Returns
    -------
    tuple of ReportRow
    """
    m = f"[{sizing.method}] "
    return (
        ReportRow(m + "allowable shear", "tau_allow", sizing.allowable_shear_pa / 1e6, "MPa"),
        ReportRow(m + "equivalent torque", "sqrt((r K M)^2 + (Kt T)^2)", sizing.equivalent_torque_n_m, "N m"),
        ReportRow(m + "diameter", sizing.formula, sizing.diameter_m * 1e3, "mm"),
        ReportRow(m + "standard diameter", "next standard >= d", sizing.standard_diameter_m * 1e3, "mm"),
    )


def handover_rows(handover: RotorHandover) -> tuple[ReportRow, ...]:
    """Rows of the hand-over to a ball-balancer study.

    Parameters
    ----------
    handover : RotorHandover
        Result of :func:`balancer.drive.shaft.rotor_handover`.

    Returns
    -------
    tuple of ReportRow
    """
    rows = [
        ReportRow("rotor speed", "from the belt ratio", handover.speed_rad_s, "rad/s"),
        ReportRow("rotor speed", "", handover.speed_rpm, "rpm"),
        ReportRow(f"shaft stiffness at rotor ({handover.layout})",
                  "3EIL/(a^2 b^2)" if handover.layout == "between bearings" else "3EI/(c^2 (L+c))",
                  handover.stiffness_n_per_m, "N/m"),
        ReportRow("rotor mode", "sqrt(k / M)", handover.rotor_natural_frequency_rad_s, "rad/s"),
    ]
    for label, speed in zip(handover.critical.partial_labels, handover.critical.partial_speeds_rad_s):
        rows.append(ReportRow(f"  partial: {label}", "", float(speed), "rad/s"))
    rows += [
        ReportRow("first critical speed", "Dunkerley 1/w^2 = sum 1/wi^2", handover.critical.critical_speed_rpm, "rpm"),
        ReportRow("critical / running", "wc / W", handover.margin.critical_to_running_ratio, "-"),
        ReportRow("separation at 1x" + ("" if handover.margin.ok_1x else "  (FAILS)"), "|wc/W - 1|",
                  handover.margin.separation_1x, "-"),
        ReportRow("separation at 2x" + ("" if handover.margin.ok_2x else "  (FAILS)"), "|wc/2W - 1|",
                  handover.margin.separation_2x, "-"),
    ]
    return tuple(rows)


def format_table(rows: Sequence[ReportRow], title: str = "") -> str:
    """Format rows as a fixed-width text table (values to 5 significant digits, at least 2 decimals).

    Parameters
    ----------
    rows : sequence of ReportRow
        The lines.
    title : str
        Optional heading.

    Returns
    -------
    str
        The table, ending with a newline.
    """
    header = ("quantity", "formula", "value", "unit")
    cells = [header] + [(r.quantity, r.formula, _number(r.value), r.unit) for r in rows]
    widths = [max(len(row[i]) for row in cells) for i in range(4)]

    def line(row: tuple[str, str, str, str]) -> str:
        return "  ".join([row[0].ljust(widths[0]), row[1].ljust(widths[1]), row[2].rjust(widths[2]), row[3]]).rstrip()

    out = [title, "=" * len(title)] if title else []
    out.append(line(header))
    out.append("  ".join("-" * w for w in widths))
    out.extend(line(row) for row in cells[1:])
    return "\n".join(out) + "\n"


def _number(value: float) -> str:
    if not math.isfinite(value):
        return str(value)
    if value != 0.0 and (abs(value) >= 1e7 or abs(value) < 1e-3):
        return f"{value:.5g}"
    digits = max(2, 4 - int(math.floor(math.log10(abs(value))))) if value != 0.0 else 2
    return f"{value:.{min(digits, 6)}f}"


def drive_report(*, drive: BeltDrive | None = None, stages: Sequence[BeltStage] = (), shaft: ShaftAnalysis | None = None,
                 sizings: Sequence[ShaftSizing] = (), handover: RotorHandover | None = None,
                 title: str = "Machine drive") -> str:
    """The whole chain as one plain-text table.

    Parameters
    ----------
    drive : BeltDrive, optional
        Stages in series (their rows come first).
    stages : sequence of BeltStage
        Further individual stages.
    shaft : ShaftAnalysis, optional
        The shaft's reactions and moments.
    sizings : sequence of ShaftSizing
        Diameter results (Soderberg and/or ASME).
    handover : RotorHandover, optional
        Speed, stiffness and critical-speed margin for the balancer.
    title : str
        Heading.

    Returns
    -------
    str
        The report.
    """
    rows: list[ReportRow] = []
    all_stages = list(drive.stages if drive is not None else ()) + list(stages)
    for stage in all_stages:
        rows.extend(belt_stage_rows(stage))
    if shaft is not None:
        rows.extend(shaft_rows(shaft))
    for sizing in sizings:
        rows.extend(sizing_rows(sizing))
    if handover is not None:
        rows.extend(handover_rows(handover))
    if not rows:
        raise ParameterError("drive_report got nothing to report; expected a drive, stages, a shaft, sizings or a hand-over")
    return format_table(rows, title)


# --------------------------------------------------------------------------- plots
def _axes(ax: Axes | None) -> tuple[Figure, Axes]:
    if ax is None:
        figure = Figure()
        return figure, figure.add_subplot()
    if not isinstance(ax, Axes):
        raise ParameterError(f"ax is a {type(ax).__name__}; expected a matplotlib Axes or None")
    return ax.get_figure(), ax


def _draw_planes(ax: Axes, analysis: ShaftAnalysis, position_m: np.ndarray, vertical: np.ndarray,
                 horizontal: np.ndarray) -> None:
    """Both planes' curves, the zero line and the bearings (triangles), x in mm."""
    ax.plot(position_m * 1e3, vertical, label="vertical plane")
    ax.plot(position_m * 1e3, horizontal, label="horizontal plane")
    ax.axhline(0.0, color="0.5", linewidth=0.8)
    for x in (analysis.geometry.bearing_a_m, analysis.geometry.bearing_b_m):
        ax.plot([x * 1e3], [0.0], marker="^", color="k", linestyle="none")


def _label(ax: Axes, ylabel: str, title: str) -> None:
    ax.set_xlabel("position (mm)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend()


def plot_shear(analysis: ShaftAnalysis, ax: Axes | None = None) -> Figure:
    """Shear-force diagram in both planes (bearings marked with triangles).

    Parameters
    ----------
    analysis : ShaftAnalysis
        Result of :func:`balancer.drive.shaft.analyse_shaft`.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new Figure is built when omitted.

    Returns
    -------
    matplotlib.figure.Figure
    """
    figure, ax = _axes(ax)
    diagram = shaft_diagram(analysis)
    _draw_planes(ax, analysis, diagram.position_m, diagram.shear_vertical_n, diagram.shear_horizontal_n)
    _label(ax, "shear force (N)", "Shear force")
    return figure


def plot_moment(analysis: ShaftAnalysis, ax: Axes | None = None) -> Figure:
    """Bending-moment diagram: each plane and the resultant.

    Parameters
    ----------
    analysis : ShaftAnalysis
        Result of :func:`balancer.drive.shaft.analyse_shaft`.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new Figure is built when omitted.

    Returns
    -------
    matplotlib.figure.Figure
    """
    figure, ax = _axes(ax)
    diagram = shaft_diagram(analysis)
    _draw_planes(ax, analysis, diagram.position_m, diagram.moment_vertical_n_m, diagram.moment_horizontal_n_m)
    ax.plot(diagram.position_m * 1e3, diagram.moment_resultant_n_m, color="k", linestyle="--", label="resultant")
    ax.plot([analysis.max_moment_position_m * 1e3], [analysis.max_moment_n_m], marker="o", color="k", linestyle="none")
    _label(ax, "bending moment (N m)", f"Bending moment (max {analysis.max_moment_n_m:.4g} N m)")
    return figure


def plot_shaft_diagrams(analysis: ShaftAnalysis, axes: Sequence[Axes] | None = None) -> Figure:
    """Shear (top) and bending-moment (bottom) diagrams of a shaft.

    Parameters
    ----------
    analysis : ShaftAnalysis
        Result of :func:`balancer.drive.shaft.analyse_shaft`.
    axes : pair of matplotlib.axes.Axes, optional
        ``(shear_ax, moment_ax)``; a new two-panel Figure is built when omitted.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if axes is None:
        figure = Figure(figsize=(7.0, 6.0), layout="constrained")
        shear_ax, moment_ax = figure.subplots(2, 1, sharex=True)
    else:
        if len(axes) != 2:
            raise ParameterError(f"axes has {len(axes)} entries; expected (shear_ax, moment_ax)")
        shear_ax, moment_ax = axes
    plot_shear(analysis, shear_ax)
    figure = plot_moment(analysis, moment_ax)
    return figure

"""Figures of a plan (matplotlib, Agg): what the paper's figures 3-6 and 8 show.

- ``plan-3d.png``: the centroid's and every UAV's path among the obstacle cylinders, the
  formation drawn at each waypoint (figures 3-4);
- ``plan-ground.png``: the projection on the ground, x-y (figure 5), with the survey's
  lanes, the via points and, with a ``[camera]``, every photo's footprint;
- ``plan-vertical.png``: the projections on the vertical planes, x-z and y-z (figure 6);
- ``convergence.png``: the best cost per iteration (figure 8, for one plan).

Axes are metres east / north / up from the area's south-west corner (the scenario's ENU
frame), altitudes above home. The ``figure_*`` functions build figures and touch no
files; :func:`figure_files` renders them to PNG, :func:`write_figures` writes them all or
none.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Polygon, Rectangle

from .mission.export import plan_missions
from .mission.files import OutputFolder
from .mission.gis import OBSTACLE_COLOUR, uav_colour
from .mission.photos import UavPhotos, plan_photos
from .planning.plans import Plan

DPI = 110
CENTROID_STYLE = dict(color="black", linestyle="--", linewidth=1.6, marker="o", markersize=3.5)
FORMATION_STYLE = dict(color="0.45", linewidth=0.9, alpha=0.8)
AREA_COLOUR = "#f3f6ee"


def _title(plan: Plan, what: str) -> str:
    s = plan.settings
    name = plan.scenario.name or Path(plan.scenario.source).stem
    status = "feasible" if plan.feasible else f"INFEASIBLE ({len(plan.violations)} violations)"
    legs = len(plan.legs)
    if legs > 1 or s.waypoints == "auto":
        shape = (f"{legs} leg{'s' if legs > 1 else ''}, {plan.waypoint_count} points"
                 + (" (auto waypoints)" if s.waypoints == "auto" else
                    f" ({s.waypoints} waypoints per leg)"))
    else:
        shape = f"{s.waypoints} waypoints"
    return f"{name}: {what}\n{s.algorithm}, seed {s.seed}, {shape}; {status}"


LANE_STYLE = dict(color="#1f5fbf", linewidth=7, alpha=0.18, solid_capstyle="butt")
PHOTO_ALPHA = 0.06
"""Each footprint's fill: overlapping photos add up to a darker shade."""
VIA_STYLE = dict(color="#1f5fbf", marker="D", markersize=6, linestyle="none")


def _lanes(plan: Plan) -> list[np.ndarray]:
    """Each survey lane as ``(2, 3)`` metres ENU (entry, exit), in flight order."""
    survey = plan.scenario.survey
    if survey is None or not survey.lanes:
        return []
    frame = plan.scenario.frame
    ends = [p for lane in survey.lanes for p in lane]
    enu = frame.to_enu(lat_deg=[p.lat_deg for p in ends], lon_deg=[p.lon_deg for p in ends],
                       alt_m=[p.alt_m for p in ends]).reshape(-1, 2, 3)
    return list(enu)


def _via(plan: Plan) -> np.ndarray:
    """The via points ``(V, 3)`` metres ENU (lane ends included)."""
    return plan.scenario.route_enu()[1:-1]


def _new_figure(width_in: float, height_in: float) -> Figure:
    fig = Figure(figsize=(width_in, height_in), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _status_colour(plan: Plan) -> str:
    return "black" if plan.feasible else "#c00000"


def _closed(points: np.ndarray) -> np.ndarray:
    """A polygon's vertices ``(N, k)`` with the first repeated at the end (N >= 3)."""
    return np.vstack([points, points[:1]]) if len(points) > 2 else points


def _photos(plan: Plan) -> list[UavPhotos]:
    """The survey's photos, from the missions the plan writes (none without a camera)."""
    if plan.scenario.survey is None or plan.scenario.survey.camera is None:
        return []
    return plan_photos(plan, plan_missions(plan))


def _legend_handles(plan: Plan, *, ground: bool, photos: list[UavPhotos] = ()) -> list:
    handles = [Line2D([], [], label="centroid", **CENTROID_STYLE)]
    handles += [
        Line2D([], [], color=uav_colour(n), linewidth=2, marker="o", markersize=4,
               label=f"uav{n + 1} (offset {_fmt_offset(off)} m)")
        for n, off in enumerate(plan.problem.offsets)
    ]
    if len(plan.problem.offsets) > 1:
        handles.append(Line2D([], [], label="formation at each waypoint", **FORMATION_STYLE))
    handles.append(Patch(facecolor=OBSTACLE_COLOUR, alpha=0.55, label="obstacle"))
    if ground:
        handles.append(Line2D([], [], color=OBSTACLE_COLOUR, linestyle=":",
                              label=f"+ clearance {plan.scenario.clearance_m:g} m"))
    if len(plan.scenario.via):
        handles.append(Line2D([], [], label="via point", **VIA_STYLE))
    if plan.scenario.survey is not None:
        sv = plan.scenario.survey
        apart = sv.lane_spacing_m if sv.lane_spacing_m is not None else sv.spacing_m
        handles.append(Line2D([], [], label=f"survey lane ({len(sv.lanes)}, "
                              f"{apart:.2f} m apart)", **LANE_STYLE))
    for n, uav in enumerate(photos):
        handles.append(Patch(facecolor=uav_colour(n), alpha=PHOTO_ALPHA * 3,
                             label=f"{uav.name} photo footprints ({uav.count})"))
    handles += [
        Line2D([], [], color="green", marker="^", linestyle="none", markersize=9, label="start"),
        Line2D([], [], color="#c00000", marker="s", linestyle="none", markersize=8, label="goal"),
    ]
    return handles


def _fmt_offset(offset) -> str:
    return "[" + ", ".join(f"{v:g}" for v in offset) + "]"


def _obstacles(plan: Plan) -> tuple[np.ndarray, np.ndarray]:
    """Axes ``(K, 2)`` metres east/north and radii ``(K,)`` without the clearance."""
    return plan.scenario.obstacles_enu()


def _extent(plan: Plan, *, margin: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal limits ``(2,)``, ``(2,)``: the area and every obstacle with its clearance."""
    lower, upper = plan.problem.area_lower.copy(), plan.problem.area_upper.copy()
    centres, radii = _obstacles(plan)
    if len(radii):
        reach = (radii + plan.scenario.clearance_m)[:, None]
        lower = np.minimum(lower, (centres - reach).min(axis=0))
        upper = np.maximum(upper, (centres + reach).max(axis=0))
    return lower - margin, upper + margin


# --------------------------------------------------------------------------- 3D


def figure_3d(plan: Plan) -> Figure:
    """3D view: cylinders, the centroid and every UAV path, the formation at each waypoint."""
    fig = _new_figure(10.0, 7.0)
    ax = fig.add_subplot(projection="3d")
    p = plan.problem
    top = p.h_max + 1.0
    centres, radii = _obstacles(plan)
    theta = np.linspace(0, 2 * np.pi, 40)
    z = np.array([0.0, top])
    for k, (c, r) in enumerate(zip(centres, radii)):
        xs = c[0] + r * np.cos(theta)[None, :] * np.ones((2, 1))
        ys = c[1] + r * np.sin(theta)[None, :] * np.ones((2, 1))
        zs = z[:, None] * np.ones((1, len(theta)))
        ax.plot_surface(xs, ys, zs, color=OBSTACLE_COLOUR, alpha=0.3, linewidth=0, shade=False)
        ax.plot(c[0] + r * np.cos(theta), c[1] + r * np.sin(theta), top,
                color=OBSTACLE_COLOUR, linewidth=0.8)
        ax.text(c[0], c[1], top + 0.3, str(k + 1), color=OBSTACLE_COLOUR, fontsize=8,
                ha="center")
    lower, upper = p.area_lower, p.area_upper
    x0, y0, x1, y1 = lower[0], lower[1], upper[0], upper[1]
    ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], 0.0, color="0.3", linewidth=1.0)
    _paths_3d(ax, plan)
    view_lo, view_hi = _extent(plan, margin=0.0)
    ax.set_xlim(view_lo[0], view_hi[0])
    ax.set_ylim(view_lo[1], view_hi[1])
    ax.set_zlim(0, top)
    size = view_hi - view_lo
    ax.set_box_aspect((size[0], size[1], 0.3 * max(size)), zoom=0.92)
    ax.view_init(elev=28, azim=-62)
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_zlabel("up (m)")
    ax.set_title(_title(plan, "3D paths (vertical scale exaggerated)"), color=_status_colour(plan))
    fig.legend(handles=_legend_handles(plan, ground=False), loc="outside right upper",
               fontsize=8)
    return fig


def _paths_3d(ax, plan: Plan) -> None:
    c, paths = plan.centroid, plan.uav_paths
    # The centroid's shadow on the ground, and a drop line from each of its waypoints,
    # tell where a path is in plan view, which a 3D projection alone hides.
    ax.plot(c[:, 0], c[:, 1], 0.0, color="0.55", linewidth=1.0, linestyle="--")
    for point in c:
        ax.plot([point[0]] * 2, [point[1]] * 2, [0.0, point[2]], color="0.7", linewidth=0.6)
    if len(paths) > 1:
        for j in range(c.shape[0]):
            ring = _closed(paths[:, j, :])
            ax.plot(ring[:, 0], ring[:, 1], ring[:, 2], **FORMATION_STYLE)
    ax.plot(c[:, 0], c[:, 1], c[:, 2], **CENTROID_STYLE)
    for n, path in enumerate(paths):
        ax.plot(path[:, 0], path[:, 1], path[:, 2], color=uav_colour(n), linewidth=2,
                marker="o", markersize=3)
    for lane in _lanes(plan):
        ax.plot(lane[:, 0], lane[:, 1], 0.0, color=LANE_STYLE["color"], linewidth=3,
                alpha=0.35)
    via = _via(plan)
    if len(via):
        ax.scatter(via[:, 0], via[:, 1], via[:, 2], color=VIA_STYLE["color"], marker="D",
                   s=25, depthshade=False)
    ax.scatter(*c[0], color="green", marker="^", s=80, depthshade=False)
    ax.scatter(*c[-1], color="#c00000", marker="s", s=60, depthshade=False)


# --------------------------------------------------------------------------- ground


def figure_ground(plan: Plan) -> Figure:
    """Ground projection (x-y): area, obstacles with clearance, paths, formation."""
    p = plan.problem
    lower, upper = p.area_lower, p.area_upper
    view_lo, view_hi = _extent(plan)
    # Equal axes: size the figure to the view so that the map fills it; the legend
    # takes about 3 in on the right, the y labels 0.8 in, titles and labels 1.5 in.
    aspect = (view_hi[1] - view_lo[1]) / (view_hi[0] - view_lo[0])
    fig = _new_figure(10.0, float(np.clip(6.2 * aspect + 1.5, 4.0, 11.0)))
    ax = fig.add_subplot()
    ax.add_patch(Rectangle(lower, *(upper - lower), facecolor=AREA_COLOUR, edgecolor="0.3",
                           linewidth=1.2, zorder=0))
    centres, radii = _obstacles(plan)
    clearance = plan.scenario.clearance_m
    for k, (c, r) in enumerate(zip(centres, radii)):
        ax.add_patch(Circle(c, r, facecolor=OBSTACLE_COLOUR, alpha=0.55, edgecolor="none",
                            zorder=1))
        if clearance > 0:
            ax.add_patch(Circle(c, r + clearance, fill=False, edgecolor=OBSTACLE_COLOUR,
                                linestyle=":", linewidth=1.0, zorder=1))
        ax.annotate(str(k + 1), (c[0], c[1] + r + clearance), textcoords="offset points",
                    xytext=(0, 2), ha="center", va="bottom", fontsize=8, color=OBSTACLE_COLOUR,
                    zorder=6, bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7))
    for k, lane in enumerate(_lanes(plan)):
        ax.plot(lane[:, 0], lane[:, 1], zorder=1, **LANE_STYLE)
        ax.annotate(f"lane {k + 1}", lane[0, :2], textcoords="offset points", xytext=(3, 3),
                    fontsize=8, color=LANE_STYLE["color"], zorder=6)
    photos = _photos(plan)
    for n, uav in enumerate(photos):
        for corners in uav.corners:
            ax.add_patch(Polygon(corners, closed=True, facecolor=uav_colour(n),
                                 alpha=PHOTO_ALPHA, edgecolor="none", zorder=1))
        if uav.count:
            ax.plot(uav.positions[:, 0], uav.positions[:, 1], linestyle="none", marker=".",
                    markersize=2.5, color=uav_colour(n), zorder=2)
    _paths_2d(ax, plan, 0, 1)
    ax.set_xlim(view_lo[0], view_hi[0])
    ax.set_ylim(view_lo[1], view_hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.grid(True, linewidth=0.4, alpha=0.5)
    ax.set_title(_title(plan, "ground projection (x-y)"), color=_status_colour(plan))
    fig.legend(handles=_legend_handles(plan, ground=True, photos=photos),
               loc="outside right upper", fontsize=8)
    return fig


def _paths_2d(ax, plan: Plan, i: int, k: int) -> None:
    """Centroid and UAV paths projected on axes ``i`` (horizontal) and ``k`` (vertical)."""
    c, paths = plan.centroid, plan.uav_paths
    if len(paths) > 1:
        for j in range(c.shape[0]):
            ring = _closed(paths[:, j, :])
            ax.plot(ring[:, i], ring[:, k], zorder=2, **FORMATION_STYLE)
    for n, path in enumerate(paths):
        ax.plot(path[:, i], path[:, k], color=uav_colour(n), linewidth=1.8, marker="o",
                markersize=3.5, zorder=3)
    ax.plot(c[:, i], c[:, k], zorder=4, **CENTROID_STYLE)
    via = _via(plan)
    if len(via):
        ax.plot(via[:, i], via[:, k], zorder=5, **VIA_STYLE)
    ax.plot(c[0, i], c[0, k], color="green", marker="^", markersize=11, linestyle="none",
            zorder=5)
    ax.plot(c[-1, i], c[-1, k], color="#c00000", marker="s", markersize=9, linestyle="none",
            zorder=5)


# --------------------------------------------------------------------------- vertical


def figure_vertical(plan: Plan) -> Figure:
    """Vertical projections: x-z (east-up) above, y-z (north-up) below, with the band."""
    fig = _new_figure(10.0, 7.5)
    axes = fig.subplots(2, 1)
    p = plan.problem
    centres, radii = _obstacles(plan)
    top = p.h_max + 1.5
    view_lo, view_hi = _extent(plan)
    for ax, i, label in ((axes[0], 0, "east"), (axes[1], 1, "north")):
        for k, (c, r) in enumerate(zip(centres, radii)):
            ax.add_patch(Rectangle((c[i] - r, 0.0), 2 * r, top, facecolor=OBSTACLE_COLOUR,
                                   alpha=0.35, edgecolor="none", zorder=1))
            ax.annotate(str(k + 1), (c[i], top), xytext=(0, -2), textcoords="offset points",
                        ha="center", va="top", fontsize=8, color=OBSTACLE_COLOUR)
        ax.axhspan(0.0, p.h_min, color="#c00000", alpha=0.06, zorder=0)
        ax.axhspan(p.h_max, top, color="#c00000", alpha=0.06, zorder=0)
        for h, name in ((p.h_min, "h_min"), (p.h_max, "h_max")):
            ax.axhline(h, color="#c00000", linewidth=0.9, linestyle="-.", zorder=1)
            ax.annotate(f"{name} {h:g} m", (1.0, h), xycoords=("axes fraction", "data"),
                        xytext=(4, 0), textcoords="offset points", va="center", fontsize=8,
                        color="#c00000")
        _paths_2d(ax, plan, i, 2)
        ax.set_xlim(view_lo[i], view_hi[i])
        ax.set_ylim(0.0, top)
        ax.set_xlabel(f"{label} (m)")
        ax.set_ylabel("up (m)")
        ax.grid(True, linewidth=0.4, alpha=0.5)
        ax.set_title(f"{'x-z' if i == 0 else 'y-z'} plane: seen from the "
                     f"{'south' if i == 0 else 'east'}", fontsize=10)
    fig.suptitle(_title(plan, "vertical projections"), color=_status_colour(plan))
    axes[0].legend(handles=_legend_handles(plan, ground=False), loc="upper left", fontsize=8,
                   bbox_to_anchor=(1.13, 1.0), borderaxespad=0)
    return fig


# --------------------------------------------------------------------------- convergence


def figure_convergence(plan: Plan) -> Figure:
    """Best cost per iteration; iterations without a feasible student are left blank."""
    fig = _new_figure(8.0, 5.0)
    ax = fig.add_subplot()
    history = np.asarray(plan.history, float)
    it = np.arange(1, len(history) + 1)
    finite = np.isfinite(history)
    ax.plot(it[finite], history[finite], color=uav_colour(0), linewidth=2,
            marker="o" if len(history) <= 30 else None, markersize=3, label="best cost")
    if finite.any():
        last = int(np.flatnonzero(finite)[-1])
        ax.plot(it[last], history[last], "o", color=uav_colour(0), markersize=6)
        ax.annotate(f"final {history[last]:.2f}", (it[last], history[last]),
                    textcoords="offset points", xytext=(-4, 8), ha="right", fontsize=9)
    else:
        ax.text(0.5, 0.5, "no feasible path in any iteration", transform=ax.transAxes,
                ha="center", fontsize=11, color="#c00000")
        ax.set_yticks([])
    if not finite.all():
        n = int((~finite).sum())
        ax.text(0.98, 0.95, f"{n} iteration{'s' if n > 1 else ''} without a feasible path "
                "(infinite cost, not drawn)", transform=ax.transAxes, ha="right", va="top",
                fontsize=9, color="#c00000")
    ax.set_xlim(0, max(len(history), 1) + 1)
    ax.set_xlabel("iteration")
    ax.set_ylabel("best cost (length m + safety + task)")
    ax.grid(True, linewidth=0.4, alpha=0.5)
    ax.set_title(_title(plan, "convergence"), color=_status_colour(plan))
    return fig


FIGURES = {
    "plan-3d.png": figure_3d,
    "plan-ground.png": figure_ground,
    "plan-vertical.png": figure_vertical,
    "convergence.png": figure_convergence,
}


def render_png(fig: Figure) -> bytes:
    """A figure as PNG bytes at its own size and resolution."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=fig.dpi)
    return buf.getvalue()


def figure_files(plan: Plan) -> dict[str, bytes]:
    """Every figure of :data:`FIGURES` as PNG bytes, by file name (no files touched)."""
    return {name: render_png(make(plan)) for name, make in FIGURES.items()}


def write_figures(plan: Plan, out_dir: str | Path) -> list[Path]:
    """Write every figure of :data:`FIGURES` into ``out_dir``, all or none; returns the paths."""
    files = figure_files(plan)
    with OutputFolder(out_dir) as out:
        return out.write_all(files)

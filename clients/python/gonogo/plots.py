"""Plots with matplotlib: traction curves, the scalability study and a map quicklook."""
import math

import numpy as np

CLASS_COLOURS = {0: ("NO-GO", "#d7191c"), 1: ("SLOW-GO", "#fdae61"), 2: ("GO", "#1a9641")}


def _points(curve):
    points = curve.points
    return points.to_records(index=False) if hasattr(points, "to_records") else points


def plot_curves(curves, labels=None, title=None):
    """Drawbar pull (kN), torque (kN m), sinkage (mm) and tractive efficiency against slip for one
    Curve or several; returns the matplotlib Figure."""
    import matplotlib.pyplot as plt
    curves = curves if isinstance(curves, (list, tuple)) else [curves]
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    panels = [("drawbar_pull_n", 1e-3, "drawbar pull D, kN"), ("torque_nm", 1e-3, "torque T, kN m"),
              ("sinkage_m", 1e3, "sinkage z, mm"), ("tractive_efficiency", 1.0, "tractive efficiency, -")]
    for i, curve in enumerate(curves):
        p = _points(curve)
        label = labels[i] if labels else f"{curve.provenance.get('tier')}, {curve.wheel_load_n / 1e3:.1f} kN"
        for ax, (field, scale, _) in zip(axes.flat, panels):
            ax.plot(p["slip"], p[field] * scale, marker=".", label=label)
    for ax, (_, _, ylabel) in zip(axes.flat, panels):
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("slip s, -")
    axes[0][0].legend(fontsize="small")
    fig.suptitle(title or "traction curve" + ("s" if len(curves) > 1 else ""))
    fig.tight_layout()
    return fig


def plot_scalability(report, title=None):
    """Seed 001's study: D/W against slip for each scale, the full-scale band shaded; returns the Figure."""
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 5))
    reference = next((r for r in report.rows if r.scale == 1.0), None)
    if reference is not None and reference.points:
        slip = np.array([p.slip for p in reference.points])
        dw = np.array([p.drawbar_pull_n for p in reference.points]) / reference.wheel_load_n
        ax.fill_between(slip, dw - report.band_drawbar_pull, dw + report.band_drawbar_pull, alpha=0.2,
                        label="full-scale band (one standard deviation)")
    for row in report.rows:
        if row.immobile_reason:
            continue
        slip = [p.slip for p in row.points]
        dw = [p.drawbar_pull_n / row.wheel_load_n for p in row.points]
        ax.plot(slip, dw, marker=".", label=f"scale {row.scale:g}: {row.drawbar_pull_inside_pct:.0f} % inside")
    ax.set_xlabel("slip s, -")
    ax.set_ylabel("drawbar-pull coefficient D/W, -")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    ax.set_title(title or "scalability: scaled tyres at equal W/(b d)")
    fig.tight_layout()
    return fig


def _nice_length(target):
    """1, 2 or 5 times a power of ten, at most `target`."""
    power = 10 ** math.floor(math.log10(target))
    return max(m * power for m in (1, 2, 5) if m * power <= target)


def quicklook(classes, title=None):
    """The GO / SLOW-GO / NO-GO raster (a gonogo.Raster) with a legend, a scale bar (projected CRS in
    metres) and a north arrow; returns the Figure."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch
    gt = classes.geotransform
    rows, cols = classes.array.shape
    extent = (gt[0], gt[0] + cols * gt[1], gt[3] + rows * gt[5], gt[3])
    data = np.ma.masked_where(~np.isin(classes.array, list(CLASS_COLOURS)), classes.array)
    fig, ax = plt.subplots(figsize=(8, 7))
    ax.imshow(data, extent=extent, cmap=ListedColormap([CLASS_COLOURS[k][1] for k in (0, 1, 2)]),
              vmin=-0.5, vmax=2.5, interpolation="nearest")
    ax.legend(handles=[Patch(color=colour, label=name) for name, colour in
                       (CLASS_COLOURS[k] for k in (2, 1, 0))], loc="upper right", fontsize="small")
    width_m = extent[1] - extent[0]
    bar = _nice_length(width_m / 4)
    x0, y0 = extent[0] + 0.05 * width_m, extent[2] + 0.05 * (extent[3] - extent[2])
    ax.plot([x0, x0 + bar], [y0, y0], color="black", linewidth=4)
    ax.text(x0 + bar / 2, y0 + 0.01 * (extent[3] - extent[2]), f"{bar / 1000:g} km" if bar >= 1000 else f"{bar:g} m", ha="center",
            va="bottom", fontsize="small")
    ax.annotate("N", xy=(0.06, 0.95), xytext=(0.06, 0.85), xycoords="axes fraction", ha="center",
                arrowprops=dict(arrowstyle="->", linewidth=1.5))
    ax.ticklabel_format(useOffset=False, style="plain")
    ax.set_xlabel("easting, m")
    ax.set_ylabel("northing, m")
    ax.set_title(title or "mobility map")
    fig.tight_layout()
    return fig

#!/usr/bin/env python3
"""Renders VTU frames of an `individual` stepping run as PNGs of the particles coloured by
their own time step Δt_i, like He et al. Fig. 1 (top): red for the smallest Δt, white for the
largest, on a log scale, projected orthographically on a plane.

usage: tools/render_dt.py INPUT [INPUT ...] [--out DIR] [--plane xy|xz|zy|...]
                          [--range DT_MIN DT_MAX] [--point-size PX] [--width PX]
                          [--view U_MIN U_MAX V_MIN V_MAX] [--order dt|depth] [--title TEXT]

INPUT is a frame file, a directory of frames, or a run directory holding frames/ (sph-run's
--out). Each frame frame_NNNNN.vtu becomes DIR/frame_NNNNN.png (default DIR: dt_frames).
All frames share one colour scale (default: the smallest and largest Δt_i over every frame
given; --range fixes it) and one view (the bounding box of every frame's particles, or
--view in metres). Particles are drawn as discs of their diameter (the median distance to
the nearest neighbour in the first frame) unless --point-size gives one in pixels.
By default the smallest steps are drawn on top, so no small step hides behind particles with
larger ones (`--order depth` draws the particle nearest the viewer on top instead; the
viewer sits on the +(u x v) side of the plane u-v: +z for xy, +y for zx, -y for xz).
The t = 0 frame has no steps yet (Δt_i = 0): such particles are drawn grey.
Exit codes: 0 ok, 2 bad input (missing file, frame without `dt`: the run was not individual).
"""
import argparse
import pathlib
import sys

from sph_python import errors_as_exit_2, need  # noqa: E402 (tools/ is the script's folder)
errors_as_exit_2()

need("numpy")
import numpy as np  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from sph_vtu import VtuError, frame_files, read_vtu  # noqa: E402

DPI = 100
AXES = {"x": 0, "y": 1, "z": 2}
BACKGROUND = "#1e1e1e"  # white particles need a dark plot area
NO_DT = (0.5, 0.5, 0.5)


def colormap():
    """Red (1, 0, 0) at the smallest Δt, white (1, 1, 1) at the largest, linear in between
    (applied to log Δt by the norm): green and blue rise together, so the map is monotonic."""
    from matplotlib.colors import LinearSegmentedColormap
    return LinearSegmentedColormap.from_list("dt_red_white", [(1.0, 0.0, 0.0), (1.0, 1.0, 1.0)])


def norm(dt_min, dt_max):
    from matplotlib.colors import LogNorm
    return LogNorm(vmin=dt_min, vmax=dt_max, clip=True)


def dt_colours(dt, dt_min, dt_max):
    """RGB (n x 3) for step sizes dt (s) on the scale [dt_min, dt_max]; grey where dt <= 0."""
    dt = np.asarray(dt, dtype=float)
    ok = np.isfinite(dt) & (dt > 0)
    rgb = np.tile(np.array(NO_DT), (len(dt), 1))
    if ok.any():
        rgb[ok] = colormap()(norm(dt_min, dt_max)(dt[ok]))[:, :3]
    return rgb


class Layout:
    """Pixel layout of one image: the plot area keeps the view's aspect ratio, the colour bar
    sits on the right. to_pixel maps plane coordinates (m) to (column, row) of the PNG."""

    def __init__(self, lo, hi, width):
        self.lo, self.hi = np.asarray(lo, float), np.asarray(hi, float)
        self.width = int(width)
        self.left, self.right_margin, self.top, self.bottom = 70, 150, 40, 50
        self.plot_w = self.width - self.left - self.right_margin
        if self.plot_w < 50:
            raise ValueError(f"--width {width}: too small, expected at least {self.left + self.right_margin + 50} px")
        ext = self.hi - self.lo
        self.plot_h = max(50, int(round(self.plot_w * ext[1] / ext[0])))
        self.height = self.plot_h + self.top + self.bottom
        # Colour bar: 20 px wide, 30 px right of the plot, as tall as the plot.
        self.cbar = (self.left + self.plot_w + 30, self.top, 20, self.plot_h)  # x, y(top), w, h in px

    def fig_rect(self, x, y_top, w, h):
        return [x / self.width, 1 - (y_top + h) / self.height, w / self.width, h / self.height]

    def to_pixel(self, u, v):
        col = self.left + (np.asarray(u) - self.lo[0]) / (self.hi[0] - self.lo[0]) * self.plot_w
        row = self.top + (self.hi[1] - np.asarray(v)) / (self.hi[1] - self.lo[1]) * self.plot_h
        return col, row


def parse_plane(text):
    t = text.lower().replace("-", "")
    if len(t) != 2 or t[0] not in AXES or t[1] not in AXES or t[0] == t[1]:
        raise ValueError(f"--plane {text}: expected two different axes of x, y, z (horizontal then vertical), e.g. xy")
    a, b = AXES[t[0]], AXES[t[1]]
    depth = 3 - a - b
    # The viewer looks along -(a x b), so the nearest particle has the largest coordinate
    # along a x b: for xy that is +z (right-handed: x right, y up, z towards the viewer).
    sign = np.cross(np.eye(3)[a], np.eye(3)[b])[depth]
    return a, b, depth, sign, t


def view_bounds(frames, a, b):
    lo = np.min([f.points[:, [a, b]].min(axis=0) for f in frames], axis=0)
    hi = np.max([f.points[:, [a, b]].max(axis=0) for f in frames], axis=0)
    pad = 0.03 * max(hi - lo) + 1e-9
    return lo - pad, hi + pad


def particle_diameter(points, sample=256, seed=1):
    """Median nearest-neighbour distance of a random sample of particles (m): the lattice
    spacing 2r for the sampled fluid. Brute force against all points, in chunks."""
    pts = np.asarray(points, dtype=float)
    if len(pts) < 2:
        return 0.0
    rng = np.random.default_rng(seed)
    pick = rng.choice(len(pts), size=min(sample, len(pts)), replace=False)
    nearest = []
    for i in pick:
        d2 = np.sum((pts - pts[i]) ** 2, axis=1)
        d2[i] = np.inf
        nearest.append(np.sqrt(d2.min()))
    return float(np.median(nearest))


def render(frame, png, layout, plane, dt_range, point_px, order="dt", title_prefix=""):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.cm import ScalarMappable

    a, b, depth, sign, name = plane
    dt = np.asarray(frame.point_data["dt"], dtype=float)
    ok = np.isfinite(dt) & (dt > 0)
    rgb = dt_colours(dt, *dt_range)
    if order == "depth":
        key = sign * frame.points[:, depth]   # farthest first, nearest drawn last
    else:
        key = np.where(ok, -dt, -np.inf)      # no-dt first, then largest to smallest
    idx = np.argsort(key, kind="stable")
    # figsize in inches with a hair of slack so Agg's int() truncation gives exactly W x H px.
    fig = plt.figure(figsize=((layout.width + 0.01) / DPI, (layout.height + 0.01) / DPI), dpi=DPI)
    ax = fig.add_axes(layout.fig_rect(layout.left, layout.top, layout.plot_w, layout.plot_h))
    ax.set_facecolor(BACKGROUND)
    ax.set_xlim(layout.lo[0], layout.hi[0])
    ax.set_ylim(layout.lo[1], layout.hi[1])
    size = (point_px * 72.0 / DPI) ** 2  # scatter sizes are in points^2
    ax.scatter(frame.points[idx, a], frame.points[idx, b], s=size, c=rgb[idx], marker="o", linewidths=0)
    ax.set_xlabel(f"{name[0]} (m)")
    ax.set_ylabel(f"{name[1]} (m)")
    active = frame.point_data.get("active")
    parts = [f"t = {frame.time:.4f} s" if frame.time is not None else "t unknown"]
    if active is not None and ok.any():
        parts.append(f"{100.0 * np.count_nonzero(active) / max(1, frame.n):.1f} % active")
    if not ok.any():
        parts.append("no Δt yet")
    ax.set_title(title_prefix + ", ".join(parts), fontsize=11)
    cax = fig.add_axes(layout.fig_rect(*layout.cbar))
    sm = ScalarMappable(norm=norm(*dt_range), cmap=colormap())
    extend = ("min" if dt[ok].min() < dt_range[0] else "neither") if ok.any() else "neither"
    if ok.any() and dt[ok].max() > dt_range[1]:
        extend = "both" if extend == "min" else "max"
    cb = fig.colorbar(sm, cax=cax, extend=extend)
    cb.set_label("Δt$_i$ (s)")
    # Labelled ticks at 1, 2, 5 x 10^k: a scale spanning one decade still reads in seconds.
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    cb.ax.yaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    cb.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    cb.ax.yaxis.set_minor_formatter(NullFormatter())
    fig.savefig(png, dpi=DPI, facecolor="white")
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("inputs", nargs="+", help="frame files, frame directories or run directories")
    ap.add_argument("--out", default="dt_frames", help="output directory for the PNGs (default dt_frames)")
    ap.add_argument("--plane", default="xy", help="projection plane, horizontal then vertical axis (default xy)")
    ap.add_argument("--range", nargs=2, type=float, metavar=("DT_MIN", "DT_MAX"),
                    help="colour scale in seconds (default: min/max of Δt_i over all frames given)")
    ap.add_argument("--point-size", type=float, default=None,
                    help="particle diameter in pixels (default: the particle spacing at the image's scale)")
    ap.add_argument("--width", type=int, default=800, help="image width in pixels (default 800)")
    ap.add_argument("--view", nargs=4, type=float, metavar=("U_MIN", "U_MAX", "V_MIN", "V_MAX"),
                    help="view rectangle in metres on the plane (default: bounding box of all frames)")
    ap.add_argument("--order", choices=("dt", "depth"), default="dt",
                    help="dt: smallest steps on top (default); depth: nearest particle on top")
    ap.add_argument("--title", default="", help="text put before the time in each title")
    args = ap.parse_args(argv)

    def fail(msg):
        print(f"render_dt.py: {msg}", file=sys.stderr)
        return 2

    try:
        plane = parse_plane(args.plane)
        files = frame_files(args.inputs)
        frames = [read_vtu(f) for f in files]
    except (VtuError, ValueError) as e:
        return fail(str(e))
    for f in frames:
        if "dt" not in f.point_data:
            return fail(f"{f.path}: no point attribute \"dt\" (per-particle time step); found "
                        f"{', '.join(f.point_data) or 'none'}. Frames carry dt only from runs in individual "
                        f"stepping mode: sph-run SCENE --mode individual (or --set simulation.stepping.mode=individual)")
        if f.n == 0:
            return fail(f"{f.path}: no particles")
    if args.range:
        lo, hi = args.range
        if not (0 < lo < hi):
            return fail(f"--range {lo:g} {hi:g}: expected 0 < DT_MIN < DT_MAX (seconds)")
        dt_range = (lo, hi)
    else:
        pos = np.concatenate([f.point_data["dt"][f.point_data["dt"] > 0] for f in frames])
        pos = pos[np.isfinite(pos)]
        if pos.size == 0:
            return fail("no frame has a positive Δt_i (only the t = 0 frame given?); pass --range DT_MIN DT_MAX")
        dt_range = (float(pos.min()), float(pos.max()))
        if dt_range[0] == dt_range[1]:
            dt_range = (dt_range[0] / 1.01, dt_range[1] * 1.01)
    if args.point_size is not None and args.point_size <= 0:
        return fail(f"--point-size {args.point_size:g}: expected a positive number of pixels")
    if args.view:
        u0, u1, v0, v1 = args.view
        if not (u0 < u1 and v0 < v1):
            return fail(f"--view {u0:g} {u1:g} {v0:g} {v1:g}: expected U_MIN < U_MAX and V_MIN < V_MAX (metres)")
        lo, hi = np.array([u0, v0]), np.array([u1, v1])
    else:
        lo, hi = view_bounds(frames, plane[0], plane[1])
    try:
        layout = Layout(lo, hi, args.width)
    except ValueError as e:
        return fail(str(e))
    point_px = args.point_size
    if point_px is None:
        point_px = max(1.0, particle_diameter(frames[0].points) * layout.plot_w / (hi[0] - lo[0]))
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"colour scale {dt_range[0]:.4g} s (red) .. {dt_range[1]:.4g} s (white), log; "
          f"images {layout.width} x {layout.height} px; particles {point_px:.1f} px")
    for f in frames:
        png = out / (f.path.stem + ".png")
        render(f, png, layout, plane, dt_range, point_px, args.order, args.title)
        print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

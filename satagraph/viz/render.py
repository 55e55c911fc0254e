r"""3D stick-figure rendering of motions with matplotlib (Agg, no display).

Several motions are drawn side by side in panels that share their scale
and camera angle, on a ground grid at y = 0, with joints in ground contact
marked. A figure that travels further than its own size is followed: its
panel is centred on the figure, smoothed over a second, and the
grid, fixed to the ground, scrolls under it (a dog trotting 10 m was a dot
in a panel that framed its whole path). Frames come out as RGB arrays
(:func:`render_frames`), and are written as a GIF (Pillow), an MP4 (imageio-ffmpeg, which bundles ffmpeg) or
a still PNG contact sheet.

Example::

    from satagraph.viz import render
    render([motion, reconstruction], "compare.gif", titles=["in", "out"],
           sheet="compare.png")

Motions are expected +Y up (canonicalise them first); units are free.
"""
from __future__ import annotations

import itertools
import math
import os
from dataclasses import dataclass
from typing import Callable, Iterable, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np

from satagraph.utils.files import atomic_path
from satagraph.motion import CONTACT_HEIGHT, CONTACT_SPEED, Motion, ground_contacts
from satagraph.sides import side_of

PathLike = Union[str, "os.PathLike[str]"]

_BONE_COLOR, _JOINT_COLOR, _CONTACT_COLOR = "#1f4e8c", "#333333", "#e4572e"
#: Bone colours of the body's middle, its left and its right side (a bone
#: takes its child joint's side, :func:`satagraph.sides.side_of`): one
#: colour for all could not tell a left step from a right one.
SIDE_COLORS = {None: _BONE_COLOR, "left": "#2a9d8f", "right": "#b5179e"}


@dataclass
class _Track:
    """What one panel shows: positions, contacts and bone segments."""

    title: str
    positions: np.ndarray  # (T, J, 3), +Y up
    contacts: np.ndarray  # (T, J) bool
    parents: np.ndarray
    fps: float
    sides: List[Optional[str]]  # per joint: "left", "right" or None


def contacts(motion: Motion, positions: Optional[np.ndarray] = None,
             height: float = CONTACT_HEIGHT, speed: float = CONTACT_SPEED
             ) -> np.ndarray:
    r"""Joints in ground contact: below ``height`` and slower than
    ``speed`` (both relative to the character height, speed per second).

    Shapes:
        - **positions**: :math:`(T, J, 3)`, optional (computed when absent)
        - **output**: :math:`(T, J)` bool
    """
    pos = motion.global_positions() if positions is None else positions
    return ground_contacts(pos, motion.fps, max(motion.height(), 1e-6), height, speed)


def _tracks(motions: Sequence[Motion], titles: Optional[Sequence[str]]
            ) -> List[_Track]:
    if not motions:
        raise ValueError("render: no motions given")
    titles = list(titles) if titles is not None else [
        os.path.basename(m.source or f"motion {i}") for i, m in enumerate(motions)]
    if len(titles) != len(motions):
        raise ValueError(f"render: {len(motions)} motions but {len(titles)} titles")
    out = []
    for motion, title in zip(motions, titles):
        if motion.num_frames == 0:
            raise ValueError(f"render: {title} has no frames")
        pos = motion.global_positions()
        out.append(_Track(title, pos, contacts(motion, pos), motion.skeleton.parents,
                          float(motion.fps), [side_of(n) for n in motion.skeleton.names]))
    return out


#: A panel follows its figure when the whole path is wider than this many
#: times the box that follows it.
FOLLOW_RATIO = 1.5


def follow_path(positions: np.ndarray, fps: float, seconds: float = 1.0) -> np.ndarray:
    r"""The figure's path on the ground (the middle of its joints, whose
    root can be far from it, at a dog's hips), averaged twice over
    :obj:`seconds` (a camera that follows it does not jitter with each
    step or arm swing); y is 0.

    Shapes:
        - **positions**: :math:`(T, J, 3)`
        - **output**: :math:`(T, 3)`
    """
    path = 0.5 * (positions.min(axis=1) + positions.max(axis=1))[:, [0, 2]]
    width = max(1, int(round(seconds * fps)))
    kernel = np.full(width, 1.0 / width)
    for _ in range(2):
        padded = np.pad(path, ((width // 2, width - 1 - width // 2), (0, 0)),
                        mode="reflect", reflect_type="odd")  # no lag at the ends
        path = np.stack([np.convolve(padded[:, k], kernel, mode="valid") for k in (0, 1)], 1)
    return np.stack([path[:, 0], np.zeros(len(path)), path[:, 1]], axis=1)


def _aim(track: _Track, frames: int) -> Tuple[np.ndarray, float]:
    """Where a panel looks on the ground, per frame, and the half width
    around it that holds the figure: the clip's centre (still), or the
    figure's smoothed path (:func:`follow_path`) when the whole clip is wider
    than :data:`FOLLOW_RATIO` times the box that follows it.

    Shapes:
        - **output**: :math:`(T, 3)` and a float
    """
    pos = track.positions[:frames]
    low, high = pos.reshape(-1, 3).min(axis=0), pos.reshape(-1, 3).max(axis=0)
    still = 0.5 * max(high[0] - low[0], high[2] - low[2], 1e-3)
    path = follow_path(track.positions, track.fps)
    reach = np.abs(pos - path[:frames, None]).max(axis=(0, 1))
    near = max(reach[0], reach[2], 1e-3)
    if still <= FOLLOW_RATIO * near:
        centre = 0.5 * (low + high) * np.array([1.0, 0.0, 1.0])
        return np.broadcast_to(centre, path.shape).copy(), still
    return path, near


def _limits(tracks: Sequence[_Track], frames: int,
            halves: Sequence[float]) -> Tuple[np.ndarray, np.ndarray]:
    """Shared (low, high) corners over all panels, around each panel's aim
    (:func:`_aim`: x and z are relative to it, :obj:`halves` the half
    widths it gives the tracks), square on the ground."""
    half = 1.05 * max(halves)
    ys = np.concatenate([t.positions[:frames, :, 1].ravel() for t in tracks])
    low, high = min(float(ys.min()), 0.0), float(ys.max())
    top = max(high, low + 0.25 * half)
    return np.array([-half, low, -half]), np.array([half, top, half])


#: Box height over ground width (:func:`panel_zoom`'s knots) and the zoom
#: at which each fits its panel, measured on renders: a walk across the
#: floor (0.35), a short walk (0.55), a figure standing still (1.8).
ZOOM_KNOTS = ((0.35, 0.55, 1.8, 4.0), (1.4, 1.05, 0.9, 0.75))


def panel_zoom(tall: float) -> float:
    """How far a panel's 3D box is magnified: 1.4 for a scene wider than
    tall, less as it grows taller, so that a figure standing still keeps
    its head and feet inside the panel (at 1.4 both were cut off)."""
    return float(np.interp(tall, *ZOOM_KNOTS))


class _Scene:
    """A figure with one 3D panel per track and persistent artists."""

    def __init__(self, tracks: Sequence[_Track], frames: int, panel_px: int,
                 elev: float, azim: float, fit: bool = False) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.tracks, self.frames = tracks, frames
        # each side's bones, by their child joints: fixed for a track, drawn every frame
        self.children = [{side: np.array([j for j in range(1, len(t.parents))
                                          if t.sides[j] == side], dtype=int)
                          for side in SIDE_COLORS} for t in tracks]
        # panels of different scales say so on the picture, not only on stderr
        self.note = "   each panel to its own scale" if fit and len(tracks) > 1 else ""
        dpi = 80
        width = 16 * round(panel_px * len(tracks) / 16)
        height = 16 * round(panel_px / 16)
        self.figure = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
        self.canvas = FigureCanvasAgg(self.figure)
        aims = [_aim(t, frames) for t in tracks]
        self.aims = [aim for aim, _ in aims]
        limits = ([_limits([t], frames, [half]) for t, (_, half) in zip(tracks, aims)] if fit
                  else [_limits(tracks, frames, [half for _, half in aims])] * len(tracks))
        self.limits = limits
        # a still panel's floor never moves: computed once, drawn into the background
        self.floors = [_ground(low, high, aim[0]) if (aim == aim[0]).all() else None
                       for aim, (low, high) in zip(self.aims, limits)]
        self.artists = [self._panel(i, t, low, high, elev, azim)
                        for i, (t, (low, high)) in enumerate(zip(tracks, limits))]
        self.label = self.figure.text(0.01, 0.01, "", fontsize=8,
                                      color="#555555", animated=True)
        self.figure.subplots_adjust(left=0, right=1, bottom=0, top=0.94, wspace=0)
        for i, track in enumerate(tracks):
            self.figure.text((i + 0.5) / len(tracks), 0.97, track.title,
                             ha="center", va="top", fontsize=9)
        if any(side is not None for track in tracks for side in track.sides):
            self._legend()
        self.canvas.draw()  # the static background, once
        self.background = self.canvas.copy_from_bbox(self.figure.bbox)

    def _legend(self) -> None:
        """"left" and "right" in their bone colours, bottom right."""
        from matplotlib.transforms import offset_copy
        right = self.figure.text(0.99, 0.01, "right", ha="right", fontsize=8,
                                 color=SIDE_COLORS["right"])
        self.figure.text(0.99, 0.01, "left", ha="right", fontsize=8, color=SIDE_COLORS["left"],
                         transform=offset_copy(right.get_transform(), fig=self.figure,
                                               x=-28, units="points"))

    def _panel(self, i: int, track: _Track, low: np.ndarray, high: np.ndarray,
               elev: float, azim: float) -> tuple:
        ax = self.figure.add_subplot(1, len(self.tracks), i + 1, projection="3d")
        # matplotlib's z is up: plot (x, z, y).
        ax.set_xlim(low[0], high[0])
        ax.set_ylim(low[2], high[2])
        ax.set_zlim(low[1], high[1])
        tall = (high[1] - low[1]) / (high[0] - low[0])
        ax.set_box_aspect((1, 1, tall), zoom=panel_zoom(tall))
        ax.view_init(elev=elev, azim=azim)
        ax.set_axis_off()
        still = self.floors[i]
        floor, = ax.plot([], [], [], color="#bbbbbb", lw=0.6, animated=still is None)
        if still is not None:
            floor.set_data_3d(still[:, 0], still[:, 2], still[:, 1])
        bones = {side: ax.plot([], [], [], color=color, lw=2, animated=True)[0]
                 for side, color in SIDE_COLORS.items()}
        joints, = ax.plot([], [], [], ls="", marker="o", ms=2.5,
                          color=_JOINT_COLOR, animated=True)
        touch, = ax.plot([], [], [], ls="", marker="o", ms=6,
                         color=_CONTACT_COLOR, animated=True)
        return ax, floor, bones, joints, touch

    def draw(self, frame: int) -> np.ndarray:
        """Update every panel to :obj:`frame` and return the RGB image
        (blitting the moving artists over the static background)."""
        self.canvas.restore_region(self.background)
        for i, (track, (ax, floor, bones, joints, touch)) in enumerate(
                zip(self.tracks, self.artists)):
            t = min(frame, len(track.positions) - 1)
            pos = self.shown(i, t)
            if self.floors[i] is None:  # a panel that follows its figure: the floor scrolls
                grid = _ground(*self.limits[i], self.aims[i][t])
                floor.set_data_3d(grid[:, 0], grid[:, 2], grid[:, 1])
                ax.draw_artist(floor)
            for side, artist in bones.items():
                seg = _segments(pos, track.parents, self.children[i][side])
                artist.set_data_3d(seg[:, 0], seg[:, 2], seg[:, 1])
            joints.set_data_3d(pos[:, 0], pos[:, 2], pos[:, 1])
            hit = pos[track.contacts[t]]
            touch.set_data_3d(hit[:, 0], hit[:, 2], hit[:, 1])
            for artist in (*bones.values(), joints, touch):
                ax.draw_artist(artist)
        self.label.set_text(f"frame {frame + 1}/{self.frames}{self.note}")
        self.figure.draw_artist(self.label)
        return np.asarray(self.canvas.buffer_rgba())[..., :3].copy()

    def shown(self, panel: int, frame: int) -> np.ndarray:
        """Panel :obj:`panel`'s joints at :obj:`frame` (held at its last),
        relative to where the panel looks then.

        Shapes:
            - **output**: :math:`(J, 3)`
        """
        track = self.tracks[panel]
        t = min(frame, len(track.positions) - 1)
        return track.positions[t] - self.aims[panel][t]


def grid_step(width: float, lines: int = 8) -> float:
    """A round spacing (1, 2 or 5 times a power of ten) that puts about
    :obj:`lines` grid lines across :obj:`width`."""
    raw = max(width / lines, 1e-9)
    power = 10.0 ** math.floor(math.log10(raw))
    return next(power * k for k in (1.0, 2.0, 5.0, 10.0) if power * k >= raw * 0.999)


def _ground(low: np.ndarray, high: np.ndarray, aim: np.ndarray) -> np.ndarray:
    """The floor seen around :obj:`aim`: its border and grid lines fixed to
    the ground (:func:`grid_step` apart), which scroll as the panel follows
    its figure, as one polyline on y = 0 relative to the aim.

    Shapes:
        - **aim**: :math:`(3,)`
        - **output**: :math:`(3L, 3)`, NaN between lines
    """
    step = grid_step(high[0] - low[0])
    lines = []
    for axis, other in ((0, 2), (2, 0)):
        first = math.ceil((aim[axis] + low[axis]) / step)
        last = math.floor((aim[axis] + high[axis]) / step)
        inner = [k * step - aim[axis] for k in range(first, last + 1)]
        cuts = [low[axis], high[axis]] + [v for v in inner  # none doubling the border
                                          if min(v - low[axis], high[axis] - v) > 0.35 * step]
        for v in cuts:
            a, b = np.zeros(3), np.zeros(3)
            a[axis] = b[axis] = v
            a[other], b[other] = low[other], high[other]
            lines += [a, b, np.full(3, np.nan)]
    return np.array(lines)


def _segments(pos: np.ndarray, parents: np.ndarray, child: np.ndarray) -> np.ndarray:
    """Bones as one polyline: (parent, child, NaN) per bone of the
    :obj:`child` joints.

    Shapes:
        - **pos**: :math:`(J, 3)`
        - **child**: :math:`(B,)` joint indices (none is the root)
        - **output**: :math:`(3B, 3)` for :math:`B` bones
    """
    seg = np.full((len(child), 3, 3), np.nan)
    seg[:, 0], seg[:, 1] = pos[parents[child]], pos[child]
    return seg.reshape(-1, 3)


def render_frames(motions: Sequence[Motion], titles: Optional[Sequence[str]] = None,
                  max_frames: Optional[int] = None, panel_px: int = 320,
                  elev: float = 15.0, azim: float = -60.0,
                  frames: Optional[Sequence[int]] = None,
                  fit: bool = False) -> Iterator[np.ndarray]:
    r"""Rendered frames, one RGB image per time step.

    Args:
        motions (list[Motion]): One motion per panel (+Y up).
        titles (list[str], optional): Panel titles (default: file names).
        max_frames (int, optional): Render at most this many frames (the
            clip is cut, not subsampled).
        panel_px (int): Panel size in pixels.
        elev (float): Camera elevation (degrees), the same for every panel.
        azim (float): Camera azimuth (degrees).
        frames (list[int], optional): Render only these frame indices.
        fit (bool): Scale each panel to its own motion (default: one scale
            for all, so that sizes compare; a crab beside a human is then a
            dot).

    Shapes:
        - **output**: :math:`(H, W, 3)` uint8 per frame
    """
    tracks = _tracks(motions, titles)
    count = frame_count(motions, max_frames)
    scene = _Scene(tracks, count, panel_px, elev, azim, fit)
    for t in (range(count) if frames is None else frames):
        yield scene.draw(int(t))


def frame_count(motions: Sequence[Motion], max_frames: Optional[int] = None) -> int:
    """Frames a rendering of :obj:`motions` has: the longest clip, capped
    by :obj:`max_frames`; shorter panels hold their last frame."""
    count = max(m.num_frames for m in motions)
    return count if max_frames is None else max(1, min(count, int(max_frames)))


def save_gif(frames: Iterable[np.ndarray], path: PathLike, fps: float) -> None:
    """Write RGB frames as a looping GIF, atomically, one frame at a time:
    memory stays bounded however long the clip (Pillow's ``save_all`` held
    every frame: 3 GB for a 3,200-frame clip). Each frame after the first
    is the box that changed, with its own palette."""
    from PIL import GifImagePlugin, Image

    duration = 10 * gif_hundredths(fps)

    def write(tmp: str) -> None:
        previous = None
        with open(tmp, "wb") as fp:
            for frame in frames:
                box = _changed_box(previous, frame)
                patch = Image.fromarray(np.ascontiguousarray(
                    frame[box[1]:box[3], box[0]:box[2]])).convert(
                    "P", palette=Image.Palette.ADAPTIVE)
                if previous is None:
                    header, _ = GifImagePlugin.getheader(patch, info={"loop": 0})
                    fp.write(b"".join(header))
                fp.write(b"".join(GifImagePlugin.getdata(
                    patch, offset=box[:2], duration=duration, include_color_table=True)))
                previous = frame
            if previous is None:
                raise ValueError("render: no frames to write")
            fp.write(b";")

    _atomic(path, write)


def _changed_box(previous: Optional[np.ndarray], frame: np.ndarray) -> Tuple[int, int, int, int]:
    """The (left, top, right, bottom) pixel box in which :obj:`frame`
    differs from :obj:`previous` (the whole frame for the first; one pixel
    where none differs, so that every time step is a frame).

    Shapes:
        - **frame**: :math:`(H, W, 3)`
    """
    h, w = frame.shape[:2]
    if previous is None:
        return 0, 0, w, h
    rows, cols = np.nonzero((previous != frame).any(axis=2))
    if len(rows) == 0:
        return 0, 0, 1, 1
    return int(cols.min()), int(rows.min()), int(cols.max()) + 1, int(rows.max()) + 1


def save_mp4(frames: Iterable[np.ndarray], path: PathLike, fps: float) -> None:
    """Write RGB frames as an H.264 MP4 with the ffmpeg bundled by
    ``imageio-ffmpeg``, atomically, one frame at a time."""
    import imageio_ffmpeg

    frames = iter(frames)
    first = next(frames)
    height, width = first.shape[:2]
    frames = itertools.chain([first], frames)
    del first  # the chain lets go of it once it is sent

    def write(tmp: str) -> None:
        writer = imageio_ffmpeg.write_frames(
            tmp, (width, height), fps=fps, codec="libx264",
            pix_fmt_out="yuv420p", macro_block_size=16, quality=7,
            output_params=["-f", "mp4"], ffmpeg_log_level="error")
        writer.send(None)
        for frame in frames:
            writer.send(np.ascontiguousarray(frame))
        writer.close()

    _atomic(path, write)


def save_sheet(frames: Sequence[np.ndarray], path: PathLike,
               columns: int = 2) -> None:
    """Tile RGB frames into one PNG contact sheet, atomically."""
    from PIL import Image

    h, w = frames[0].shape[:2]
    rows = -(-len(frames) // columns)
    sheet = np.full((rows * h, min(columns, len(frames)) * w, 3), 255, np.uint8)
    for i, frame in enumerate(frames):
        r, c = divmod(i, columns)
        sheet[r * h:(r + 1) * h, c * w:(c + 1) * w] = frame
    _atomic(path, lambda tmp: Image.fromarray(sheet).save(tmp, format="PNG"))


def _reported(frames: Iterable[np.ndarray], total: int,
              progress: Optional[Callable[[int, int], None]]) -> Iterator[np.ndarray]:
    """:obj:`frames`, ``progress(drawn, total)`` called as each is drawn."""
    for drawn, frame in enumerate(frames, 1):
        if progress is not None:
            progress(drawn, total)
        yield frame


def _atomic(path: PathLike, write) -> None:
    """Run ``write(tmp)`` on a temporary file beside :obj:`path`, then move
    it into place (:func:`satagraph.utils.files.atomic_path`)."""
    with atomic_path(path) as tmp:
        write(tmp)


def sheet_frames(count: int, samples: int = 6) -> List[int]:
    """Evenly spaced frame indices for a contact sheet."""
    return sorted({int(round(v)) for v in np.linspace(0, count - 1, min(samples, count))})


def display_rate(motions: Sequence[Motion], ext: str, fps: Optional[float] = None) -> float:
    """Frames per second an animation shows: :obj:`fps`, else the first
    motion's; for a GIF the nearest rate it plays exactly, at most 50 (its
    frame delays are whole hundredths of a second: a 120 fps clip written
    at 20 ms a frame played 2.4 times slow, a 30 fps one at 30 ms 1.11
    times fast)."""
    rate = float(fps or motions[0].fps)
    _check_rate(rate)
    return 100.0 / gif_hundredths(rate) if ext == ".gif" else rate


def gif_hundredths(rate: float) -> int:
    """A GIF frame's delay for :obj:`rate` frames per second, in the whole
    hundredths of a second a GIF stores (at least 2: 50 fps)."""
    return max(2, int(round(100.0 / rate)))


def _check_rate(rate: float) -> None:
    if not (math.isfinite(rate) and 0 < rate <= MAX_RATE):
        raise ValueError(f"render: the frame rate must be above 0 and at most "
                         f"{MAX_RATE:g}, got {rate:g}")


#: The highest frame rate an animation is drawn at.
MAX_RATE = 1000.0


def on_clock(motions: Sequence[Motion], rate: float,
             max_frames: Optional[int] = None) -> List[Motion]:
    """Every motion resampled to :obj:`rate` frames per second
    (:func:`~satagraph.transforms.canonical.resample`), so that panels of
    different rates show the same instant in each frame (they were lined
    up by frame index: a 60 fps panel beside 30 fps ones ran twice as fast,
    then stood); with :obj:`max_frames`, only the time those frames show
    is resampled.

    Raises:
        ValueError: :obj:`rate` is not a positive number up to
            :data:`MAX_RATE`.
    """
    from satagraph.transforms.canonical import resample
    _check_rate(rate)
    out = []
    for m in motions:
        if max_frames is not None:
            m = m.slice(0, min(m.num_frames, int(math.ceil(max_frames / rate * m.fps)) + 1))
        out.append(m if m.num_frames < 2 or abs(m.fps - rate) < 1e-9 else resample(m, rate))
    return out


def render(motions: Union[Motion, Sequence[Motion]], path: Optional[PathLike] = None,
           titles: Optional[Sequence[str]] = None, fps: Optional[float] = None,
           max_frames: Optional[int] = None, sheet: Optional[PathLike] = None,
           panel_px: int = 320, elev: float = 15.0, azim: float = -60.0,
           fit: bool = False, progress: Optional[Callable[[int, int], None]] = None) -> int:
    r"""Render motions side by side to a GIF or MP4 and/or a PNG sheet.

    Args:
        motions (Motion or list[Motion]): One motion per panel (+Y up).
        path (str or PathLike, optional): ``.gif`` or ``.mp4`` output.
        titles (list[str], optional): Panel titles (default: file names).
        fps (float, optional): Frames per second shown (default: the first
            motion's; for a GIF the nearest rate it plays exactly,
            :func:`display_rate`); every panel is resampled to it
            (:func:`on_clock`), so the animation runs in real time and its
            panels together.
        max_frames (int, optional): Cut the animation to this many frames.
        sheet (str or PathLike, optional): PNG contact sheet of six evenly
            spaced frames.
        panel_px (int): Panel size in pixels.
        elev (float): Camera elevation (degrees).
        azim (float): Camera azimuth (degrees).
        fit (bool): Scale each panel to its own motion (see
            :func:`render_frames`).
        progress (callable, optional): Called as ``progress(drawn, total)``
            after each animation frame is drawn (a long take draws about 50
            frames a second on a 2-core CPU: ``satagraph render`` shows the
            count with :class:`~satagraph.cli.progress.ProgressLine`).

    Returns:
        int: The number of animation frames.
    """
    motions = [motions] if isinstance(motions, Motion) else list(motions)
    if path is None and sheet is None:
        raise ValueError("render: give an output path and/or a sheet path")
    ext = "" if path is None else os.path.splitext(os.fspath(path))[1].lower()
    if path is not None and ext not in (".gif", ".mp4"):
        raise ValueError(f"render: output must be .gif or .mp4, got {os.fspath(path)!r}")
    if ext == ".mp4":
        import imageio_ffmpeg  # noqa: F401  (the viz extra): missing is said before any work
    fps = display_rate(motions, ext, fps)
    motions = on_clock(motions, fps, max_frames)
    count = frame_count(motions, max_frames)
    kwargs = dict(titles=titles, max_frames=max_frames, panel_px=panel_px,
                  elev=elev, azim=azim, fit=fit)
    if path is not None:  # frames drawn as they are written, never all held
        frames = _reported(render_frames(motions, **kwargs), count, progress)
        (save_gif if ext == ".gif" else save_mp4)(frames, path, fps)
    if sheet is not None:
        picks = sheet_frames(count)
        save_sheet(list(render_frames(motions, frames=picks, **kwargs)), sheet,
                   columns=1 if len(motions) > 2 else 2)
    return count

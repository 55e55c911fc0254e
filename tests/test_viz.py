"""Rendering: GIF, MP4 and PNG contact sheets, and ``satagraph render``."""
from __future__ import annotations

import numpy as np
import pytest

PIL = pytest.importorskip("PIL")
pytest.importorskip("matplotlib")

from PIL import Image  # noqa: E402

from satagraph.cli import main  # noqa: E402
from satagraph.data.examples import example_motion  # noqa: E402
from satagraph.datasets.zoo import generate_clip, zoo_rigs  # noqa: E402
from satagraph.io import write_bvh  # noqa: E402
from satagraph.viz import contacts, frame_count, render, render_frames  # noqa: E402
from satagraph.viz.render import display_rate, on_clock  # noqa: E402


@pytest.fixture(scope="module")
def motions():
    rigs = zoo_rigs(["quadruped"], seed=0)
    return [example_motion(num_frames=12),
            generate_clip(rigs[0], "trot", frames=10, seed=0)]


def test_gif_has_one_frame_per_time_step(tmp_path, motions):
    """At 30 fps a GIF (whole hundredths of a second a frame) plays 33.3
    frames a second exactly: 12 frames of 30 fps are 13 of it."""
    path = tmp_path / "a.gif"
    count = render(motions, path, titles=["walk", "dog"], panel_px=160)
    assert count == 13 == frame_count(on_clock(motions, 100 / 3))
    with Image.open(path) as gif:
        assert gif.n_frames == 13 and gif.info["duration"] == 30
        assert gif.size == (320, 160)
        gif.seek(5)
        assert np.asarray(gif.convert("L")).std() > 5  # not blank


def test_max_frames_and_fps(tmp_path, motions):
    path = tmp_path / "b.gif"
    assert render(motions, path, fps=10, max_frames=4, panel_px=96) == 4
    with Image.open(path) as gif:
        assert gif.n_frames == 4
        assert gif.info["duration"] == 100


def test_panels_of_other_rates_play_in_real_time_together(tmp_path, motions):
    """A 120 fps clip was written at 20 ms a frame (2.4 times slow), and a
    60 fps panel beside a 30 fps one ran twice as fast, then stood."""
    from satagraph.transforms.canonical import resample
    fast = resample(motions[0], 120.0)
    assert display_rate([fast], ".gif") == 50.0 and display_rate([fast], ".mp4") == 120.0
    assert display_rate([motions[0]], ".gif", fps=24) == 25.0
    pair = on_clock([fast, motions[0]], 50.0)
    assert [m.fps for m in pair] == [50.0, 50.0]
    assert pair[0].num_frames == pair[1].num_frames  # the same 0.37 s each
    np.testing.assert_allclose(pair[0].global_positions(), pair[1].global_positions(),
                               atol=1e-6)
    path = tmp_path / "fast.gif"
    count = render([fast], path, panel_px=96)
    with Image.open(path) as gif:
        seconds = gif.n_frames * gif.info["duration"] / 1000
    assert count == gif.n_frames and abs(seconds - motions[0].duration) < 0.03


def test_a_frame_rate_past_reason_is_one_line_and_a_cut_is_cut_first(tmp_path, motions):
    """``--fps inf`` was a traceback (and a GIF silently 50 fps); ``1e9``
    resampled every clip whole before ``--max-frames`` cut it: killed."""
    for fps in (float("inf"), 1e9, float("nan")):
        for name in ("a.gif", "a.mp4"):
            with pytest.raises(ValueError, match="frame rate must be above 0 and at most 1000"):
                render(motions, tmp_path / name, fps=fps)
    cut = on_clock(motions, 1000.0, max_frames=5)
    assert all(m.num_frames <= 34 for m in cut)  # a frame of 30 fps, not the 367 of the clip


def test_mp4(tmp_path, motions):
    ffmpeg = pytest.importorskip("imageio_ffmpeg")
    path = tmp_path / "a.mp4"
    assert render(motions, path, panel_px=160) == 12
    assert path.stat().st_size > 1000
    frames, _ = ffmpeg.count_frames_and_secs(str(path))
    assert frames == 12


def test_png_sheet(tmp_path, motions):
    path = tmp_path / "sheet.png"
    render(motions, sheet=path, panel_px=128)
    with Image.open(path) as sheet:
        assert sheet.format == "PNG"
        assert sheet.size[0] == 2 * 256 and sheet.size[1] % 128 == 0


def test_frames_differ_and_contacts_marked(motions):
    frames = list(render_frames(motions[:1], panel_px=96, frames=[0, 6]))
    assert frames[0].shape == (96, 96, 3)
    assert not np.array_equal(frames[0], frames[1])
    touch = contacts(motions[0])
    assert touch.shape == (12, motions[0].num_joints)
    assert 0 < touch.mean() < 0.5


def test_bad_output(tmp_path, motions):
    with pytest.raises(ValueError):
        render(motions, tmp_path / "a.avi")
    with pytest.raises(ValueError):
        render(motions)


def test_render_blits_instead_of_redrawing(tmp_path, monkeypatch):
    """The static background is drawn once; every frame only blits the
    moving artists over it (full redraws were several times slower)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    draws = []
    real_draw = FigureCanvasAgg.draw

    def counting_draw(self, *args, **kwargs):
        draws.append(self)
        return real_draw(self, *args, **kwargs)

    monkeypatch.setattr(FigureCanvasAgg, "draw", counting_draw)
    clip = example_motion(num_frames=12)
    count = render([clip, clip], tmp_path / "fast.gif", panel_px=160)
    assert len(draws) == 1
    assert Image.open(tmp_path / "fast.gif").n_frames == count


@pytest.mark.parametrize("ext", [".gif", ".mp4"])
def test_a_long_clip_is_written_frame_by_frame(tmp_path, monkeypatch, ext):
    """Frames are written as they are drawn: at most three are alive at any
    time however long the clip (every frame was held, then handed to
    Pillow, which held them again: 3 GB for a 3,200-frame clip), and the
    GIF still has one frame per time step, each of the same picture."""
    import weakref
    if ext == ".mp4":
        pytest.importorskip("imageio_ffmpeg")
    from satagraph.viz.render import _Scene
    alive, drawn = [], []
    real_draw = _Scene.draw

    def counting_draw(self, frame):
        image = real_draw(self, frame)
        alive.append(sum(ref() is not None for ref in drawn) + 1)
        drawn.append(weakref.ref(image))
        return image

    monkeypatch.setattr(_Scene, "draw", counting_draw)
    clip = example_motion(num_frames=40)
    path = tmp_path / f"long{ext}"
    count = render(clip, path, fps=25, panel_px=96)
    assert count == len(alive) == 33 and max(alive) <= 3
    if ext == ".gif":
        monkeypatch.setattr(_Scene, "draw", real_draw)
        picks = [0, 17, 32]
        expected = list(render_frames(on_clock([clip], 25.0), panel_px=96, frames=picks))
        with Image.open(path) as gif:
            assert gif.n_frames == 33 and gif.info["duration"] == 40
            for index, want in zip(picks, expected):
                gif.seek(index)
                got = np.asarray(gif.convert("RGB")).astype(int)
                assert np.abs(got - want).mean() < 2.0


def test_a_missing_optional_package_is_one_line_before_any_work(tmp_path, capsys,
                                                                monkeypatch):
    """Without the viz extra an MP4 was a traceback after every frame was
    drawn; a plain install's missing matplotlib took the demo down the same
    way (it is a dependency now)."""
    import sys
    bvh = tmp_path / "walk.bvh"
    write_bvh(example_motion(num_frames=8), bvh)
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)
    assert main(["render", str(bvh), str(tmp_path / "a.mp4")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'imageio_ffmpeg'" in err and "satagraph[viz]" in err
    assert not (tmp_path / "a.mp4").exists()
    assert main(["generate", "--text", "a person walks", "--skeleton", str(bvh), "--seconds",
                 "1", "--render", str(tmp_path / "g.mp4"), str(tmp_path / "g.bvh")]) == 2
    assert "satagraph[viz]" in capsys.readouterr().err and not (tmp_path / "g.bvh").exists()


def test_progress_is_called_as_each_frame_is_drawn(tmp_path, motions):
    """A long take's render said nothing until it ended (51 s of a dog's
    clip: a minute of silence); ``progress(drawn, total)`` now counts the
    animation's frames as they are drawn (the sheet's six are not counted)."""
    calls = []
    count = render(motions, tmp_path / "p.gif", fps=10, max_frames=4, panel_px=64,
                   sheet=tmp_path / "p.png", progress=lambda *a: calls.append(a))
    assert count == 4 and calls == [(1, 4), (2, 4), (3, 4), (4, 4)]


def test_cli_render(tmp_path, capsys):
    bvh = tmp_path / "walk.bvh"
    write_bvh(example_motion(num_frames=8), bvh)
    out, sheet = tmp_path / "out.gif", tmp_path / "sheet.png"
    assert main(["render", str(bvh), str(bvh), str(out), "--png", str(sheet),
                 "--max-frames", "5"]) == 0
    assert "wrote" in capsys.readouterr().out
    with Image.open(out) as gif:
        assert gif.n_frames == 5
    assert sheet.stat().st_size > 0
    assert main(["render", str(bvh), str(tmp_path / "x.txt")]) == 2
    # files after an option, as `render A.bvh --max-frames 3 B.bvh OUT.gif`
    assert main(["render", str(bvh), "--max-frames", "3", str(bvh), str(out)]) == 0
    with Image.open(out) as gif:
        assert gif.n_frames == 3


def test_cli_render_takes_units_per_file(tmp_path, capsys):
    """``--units cm,m``: a rig in centimetres beside one in metres are both
    drawn at their true size (one value for every file stays as before; a
    list of another length is one error line)."""
    from satagraph.cli import build_parser
    from satagraph.cli.arguments import read_with_rig
    from satagraph.cli.render import _shown

    def _load(path, args, index):
        return _shown(read_with_rig(path, args, index=index), False)
    walk = example_motion(num_frames=4)
    cm = tmp_path / "cm.bvh"
    write_bvh(walk.with_(translations=walk.translations * 100.0,
                         skeleton=walk.skeleton.replace(offsets=walk.skeleton.offsets * 100.0)),
              cm)
    metres = tmp_path / "m.bvh"
    write_bvh(walk, metres)
    out = tmp_path / "out.gif"
    argv = ["render", str(cm), str(metres), str(out), "--units", "cm,m"]
    args = build_parser().parse_args(argv)
    heights = [_load(str(path), args, i).height() for i, path in enumerate((cm, metres))]
    assert heights[0] == pytest.approx(heights[1], rel=1e-6)
    assert heights[1] == pytest.approx(walk.height(), rel=0.05)
    assert main(argv + ["--max-frames", "2"]) == 0
    one = build_parser().parse_args(["render", str(cm), str(cm), str(out), "--units", "cm"])
    assert [_load(str(cm), one, i).height() for i in (0, 1)] == [heights[0]] * 2
    assert main(["render", str(cm), str(metres), str(out), "--units", "cm,m,in"]) == 2
    assert "--units has 3 values for 2 files" in capsys.readouterr().err
    # auto: that file's units guessed, as without the option
    plain = build_parser().parse_args(["render", str(cm), str(metres), str(out)])
    mixed = build_parser().parse_args(["render", str(cm), str(metres), str(out),
                                       "--units", "cm,auto", "--up-axis", "auto,y"])
    assert mixed.units == [0.01, None] and mixed.up_axis == [None, "+Y"]
    assert _load(str(metres), mixed, 1).height() == pytest.approx(
        _load(str(metres), plain, 1).height(), rel=1e-9)
    assert _load(str(cm), mixed, 0).height() == pytest.approx(heights[0], rel=1e-6)


def _outside(motion, zoom=None) -> int:
    """How many joint positions of the first frame project outside their
    panel (``zoom``: force the box zoom, as before :func:`panel_zoom`)."""
    import importlib
    from mpl_toolkits.mplot3d import proj3d
    module = importlib.import_module("satagraph.viz.render")
    scene = module._Scene(module._tracks([motion], None), 1, 320, 15.0, -60.0)
    ax = scene.artists[0][0]
    if zoom is not None:
        low, high = scene.limits[0]
        ax.set_box_aspect((1, 1, (high[1] - low[1]) / (high[0] - low[0])), zoom=zoom)
        scene.canvas.draw()
    return int((~_inside(scene, 0, 0)[0]).sum())


def _inside(scene, panel: int, frame: int):
    """Which of a panel's joints at ``frame`` project inside the panel, and
    the figure's projected height in pixels."""
    from mpl_toolkits.mplot3d import proj3d
    ax = scene.artists[panel][0]
    box = ax.get_window_extent()
    pos = scene.shown(panel, frame)
    x, y, _ = proj3d.proj_transform(pos[:, 0], pos[:, 2], pos[:, 1], ax.get_proj())
    px = ax.transData.transform(np.stack([x, y], axis=1))
    inside = ((px[:, 0] >= box.x0) & (px[:, 0] <= box.x1)
              & (px[:, 1] >= box.y0) & (px[:, 1] <= box.y1))
    return inside, float(np.ptp(px[:, 1]))


def test_a_figure_standing_still_keeps_its_head_and_feet_in_the_panel():
    """A standing figure's box is tall (height over ground width about 2):
    at the old fixed zoom (1.4) its head and feet projected outside the
    panel; :func:`panel_zoom` keeps every joint inside, and a scene wider
    than tall keeps 1.4."""
    from satagraph.viz.render import panel_zoom
    rig = [r for r in zoo_rigs(seed=0) if r.species == "biped"][0]
    still = generate_clip(rig, "idle", frames=4, seed=0)
    assert _outside(still, zoom=1.4) > 0
    assert _outside(still) == 0
    assert panel_zoom(0.2) == 1.4 and panel_zoom(0.35) == 1.4
    assert 1.4 > panel_zoom(0.8) > panel_zoom(1.8) > panel_zoom(3.0) >= 0.75


def test_a_figure_that_travels_is_followed_large_and_in_the_panel():
    """A biped running 10 m in 5 s, beside one standing: the panels framed
    the whole run, which drew both figures at a fifth of the panel's height;
    each panel now follows its figure (the run's aim moves smoothly, the
    idle's not at all), one scale for both, every joint in the panel."""
    import importlib
    module = importlib.import_module("satagraph.viz.render")
    rig = [r for r in zoo_rigs(seed=0) if r.species == "biped"][0]
    run = generate_clip(rig, "run", frames=150, seed=0)
    idle = generate_clip(rig, "idle", frames=150, seed=0)
    scene = module._Scene(module._tracks([run, idle], None), 150, 320, 15.0, -60.0)
    for panel in range(2):
        seen = [_inside(scene, panel, t) for t in range(0, 150, 10)]
        assert all(inside.all() for inside, _ in seen)
        assert min(height for _, height in seen) > 0.45 * 320
    step = np.diff(scene.aims[0], axis=0)
    assert np.ptp(scene.aims[0][:, 2]) > 8.0  # it follows the run
    assert np.abs(np.diff(step, axis=0)).max() < 0.05 * np.linalg.norm(step, axis=1).max()
    assert np.ptp(scene.aims[1], axis=0).max() == 0.0  # a still camera
    grid = module._ground(*scene.limits[0], scene.aims[0][40])
    later = module._ground(*scene.limits[0], scene.aims[0][41])
    assert grid.shape != later.shape or not np.allclose(grid, later, equal_nan=True)


def test_fit_scales_each_panel_to_its_own_figure():
    """A figure beside its copy at a tenth of the size: one shared scale
    draws the copy ten times smaller; ``fit`` draws both alike."""
    import importlib
    module = importlib.import_module("satagraph.viz.render")
    walk = example_motion(num_frames=4)
    small = walk.with_(translations=walk.translations * 0.1,
                       skeleton=walk.skeleton.replace(offsets=walk.skeleton.offsets * 0.1))

    def heights(fit: bool):
        scene = module._Scene(module._tracks([walk, small], None), 1, 200, 15.0, -60.0, fit)
        return [_inside(scene, i, 0)[1] for i in range(2)]

    shared, fitted = heights(False), heights(True)
    assert shared[1] == pytest.approx(0.1 * shared[0], rel=0.05)
    assert fitted[1] == pytest.approx(fitted[0], rel=0.02)


def test_panels_of_unknown_units_are_each_scaled_to_their_own_figure(shared_data, tmp_path,
                                                                     capsys, monkeypatch):
    """The dog's files are in centimetres that no reading can tell (read as
    metres it is 50 m tall): beside a human it would dwarf him to a dot, so
    each panel is scaled to its own figure and one line names the file whose
    ``--units`` to give; with them, or with one panel, one scale for all."""
    import satagraph.viz
    dog = shared_data / "dog" / "D1_013_KAN01_001.bvh"
    human = shared_data / "bandai" / "dataset-1_walk_normal_001.bvh"
    seen = []
    monkeypatch.setattr(satagraph.viz, "render",
                        lambda motions, *a, fit=False, **k: seen.append(fit) or 1)
    out = str(tmp_path / "out.gif")
    assert main(["render", str(dog), str(human), out]) == 0
    assert "units unknown for D1_013_KAN01_001.bvh (pass --units)" in capsys.readouterr().err
    assert main(["render", str(dog), str(human), out, "--units", "cm"]) == 0
    assert main(["render", str(dog), out]) == 0
    assert "units unknown" not in capsys.readouterr().err
    assert seen == [True, False, False]


def test_left_and_right_bones_are_drawn_apart():
    """A biped's left bones are drawn in one colour and its right ones in
    another (one colour for all could not tell a left step from a right
    one), its middle in a third; a legend names the two sides."""
    from matplotlib.colors import to_rgb
    from satagraph.sides import side_of
    from satagraph.viz.render import SIDE_COLORS
    clip = example_motion(num_frames=2)
    sides = [side_of(name) for name in clip.skeleton.names]
    assert sides.count("left") >= 3 and sides.count("left") == sides.count("right")
    image = next(render_frames([clip], panel_px=320)).astype(int)

    def pixels(side) -> int:
        color = np.array(to_rgb(SIDE_COLORS[side])) * 255
        return int((np.abs(image - color).max(axis=2) < 12).sum())

    assert pixels("left") > 50 and pixels("right") > 50 and pixels(None) > 50


def test_panels_to_their_own_scales_say_so_on_the_picture():
    """Panels each scaled to its own figure (``fit``) compare no sizes: the
    picture says so under them (only a line on stderr did); one scale for
    all, or one panel, says nothing."""
    import importlib
    module = importlib.import_module("satagraph.viz.render")
    walk = example_motion(num_frames=2)

    def label(motions, fit: bool) -> str:
        scene = module._Scene(module._tracks(motions, None), 2, 160, 15.0, -60.0, fit)
        scene.draw(1)
        return scene.label.get_text()

    assert label([walk, walk], True) == "frame 2/2   each panel to its own scale"
    assert label([walk, walk], False) == "frame 2/2" == label([walk], True)

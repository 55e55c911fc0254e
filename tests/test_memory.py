import sys
import subprocess

import pytest


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc mallopt is Linux-only")
def test_retain_freed_memory_takes_effect_in_a_fresh_process():
    code = "from satagraph.memory import retain_freed_memory; print(retain_freed_memory())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "True"


BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  End Site
  {
    OFFSET 0 10 0
  }
}
MOTION
Frames: 2
Frame Time: 0.033333
0 90 0 0 0 0
1 90 0 0 0 10
"""


def test_cli_main_sets_it(monkeypatch, tmp_path, capsys):
    import satagraph.cli as cli
    calls = []
    monkeypatch.setattr(cli, "retain_freed_memory", lambda: calls.append(1) or True)
    path = tmp_path / "one.bvh"
    path.write_text(BVH)
    assert cli.main(["inspect", str(path)]) == 0
    assert calls == [1]
    assert "Hips" in capsys.readouterr().out

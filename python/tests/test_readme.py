"""The Python examples of the READMEs run as written (from the repository root)."""

import re

import pytest

from conftest import ROOT


def python_blocks(path):
    return re.findall(r"```python\n(.*?)```", path.read_text(), flags=re.S)


def test_the_package_readme_example_runs(monkeypatch, capsys):
    blocks = python_blocks(ROOT / "python" / "README.md")
    assert len(blocks) == 3
    monkeypatch.chdir(ROOT)
    exec(compile(blocks[0], "python/README.md", "exec"), {})
    out = capsys.readouterr().out
    # README's table of `grainchain reproduce`: gamma of (a) over [400, 4000] is 0.849 (of
    # E_R in percent, the same slope as of E_R itself).
    assert re.fullmatch(r"gamma = 0\.849 \[0\.\d{3}, 0\.\d{3}\]\n", out), out


def test_the_package_readme_protector_example_runs(monkeypatch, capsys):
    blocks = python_blocks(ROOT / "python" / "README.md")
    monkeypatch.chdir(ROOT)
    exec(compile(blocks[1], "python/README.md protector", "exec"), {})
    out = capsys.readouterr().out
    # examples/protector.rs prints the same two designs: 21.3 N and 145.3 N.
    assert out == "peak on the wall: 21.3 N against 145.3 N\n", out


def test_the_package_readme_monte_carlo_example_runs(monkeypatch, capsys):
    """The tolerance example follows the protector one (its designs and load)."""
    blocks = python_blocks(ROOT / "python" / "README.md")
    monkeypatch.chdir(ROOT)
    exec(compile(blocks[1] + blocks[2], "python/README.md monte carlo", "exec"), {})
    out = capsys.readouterr().out.splitlines()[-1]
    m = re.fullmatch(r"p95 of the peak: (\S+) N, 95 % interval \[(\S+), (\S+)\] N", out)
    assert m, out
    value, low, high = map(float, m.groups())
    # A percentile lies within its order-statistic interval, whose ends are two of the peaks.
    assert low <= value <= high, out


def test_the_root_readme_python_section_runs(monkeypatch):
    blocks = python_blocks(ROOT / "README.md")
    if not blocks:
        pytest.skip("README.md has no ```python block yet")
    monkeypatch.chdir(ROOT)
    for k, b in enumerate(blocks):
        exec(compile(b, f"README.md python block {k + 1}", "exec"), {})

"""``rotor report``, ``rotor loads`` and ``rotor balance``: the report
folder (one self-contained page, its figures as PNG, its tables as CSV), written whole or
not at all; its numbers are the library's; the page renders in a headless browser.

One report is written for the module (4chn15, tables every 30°), through the command line,
into a folder that holds a previous report, which it must replace; a folder holding
anything the report did not write is refused, and what is there kept."""

from __future__ import annotations

import base64
import csv
import json
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest
from conftest import run_cli

import rotor

STEP = 30.0
HTTP = re.compile(r"(?:https?:)?//[\w.-]+\.\w", re.IGNORECASE)


def read_csv(path: str | Path) -> dict[str, np.ndarray]:
    with open(path, encoding="utf-8", newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    cols: dict[str, np.ndarray] = {}
    for i, name in enumerate(header):
        values = [r[i] for r in body]
        try:
            cols[name] = np.array([float(v) if v else np.nan for v in values])
        except ValueError:
            cols[name] = np.array(values)
    return cols


@pytest.fixture(scope="module")
def engine() -> rotor.Engine:
    return rotor.load_engine("4chn15")


def previous_report(out: Path, figures: dict[str, bytes] | None = None) -> None:
    """A report put in place at ``out`` by :func:`rotor.design.report.report_folder` (which
    records its files): ``figures`` (name: bytes), a table and a page."""
    from rotor.design.report import report_folder

    with report_folder(str(out)) as tmp:
        os.mkdir(os.path.join(tmp, "figures"))
        os.mkdir(os.path.join(tmp, "tables"))
        for name, data in (figures or {"old.png": b"old"}).items():
            Path(tmp, "figures", name).write_bytes(data)
        Path(tmp, "tables", "old.csv").write_text("a\n1\n")
        Path(tmp, "index.html").write_text("<p>an older report</p>\n")


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """``rotor report 4chn15 --out DIR --step 30 --json`` over a previous report in DIR."""
    root = tmp_path_factory.mktemp("report")
    out = root / "r"
    previous_report(out, {"stale.png": b"old"})
    rc, text, _ = run_cli(None, "report", "4chn15", "--out", out, "--step", STEP, "--json")
    assert rc == 0, text
    data = json.loads(text)
    data["root"] = root
    return data


@pytest.fixture(scope="module")
def page(written: dict) -> str:
    return Path(written["page"]).read_text(encoding="utf-8")


def test_the_folder_holds_the_page_figures_and_tables_and_nothing_else(written: dict) -> None:
    out = Path(written["out_dir"])
    assert sorted(os.listdir(out)) == [".rotor-report.json", "figures", "index.html", "tables"]
    figures = sorted(os.listdir(out / "figures"))
    tables = sorted(os.listdir(out / "tables"))
    assert figures == sorted(Path(p).name for p in written["figures"])
    assert tables == sorted(Path(p).name for p in written["tables"])
    assert "stale.png" not in figures  # the previous report was replaced whole
    for name in figures:
        assert (out / "figures" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    assert not [p for p in os.listdir(written["root"]) if p.startswith(".rotor")], "a temporary folder was left"
    assert written["step_deg"] == STEP and written["figure_step_deg"] == 1.0
    assert written["rpm"] == 1250.0 and written["kinematics"] == "exact"


def test_the_record_lists_every_file_written_with_its_digest(written: dict) -> None:
    import hashlib

    out = Path(written["out_dir"])
    record = json.loads((out / ".rotor-report.json").read_text(encoding="utf-8"))
    assert record["written_by"] == "rotor report"
    on_disk = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert sorted(record["files"]) == [n for n in on_disk if n != ".rotor-report.json"]
    assert "figures/stale.png" not in record["files"] and "tables/old.csv" not in record["files"]
    for name, digests in record["files"].items():
        assert digests == [hashlib.sha256((out / name).read_bytes()).hexdigest()], name


def test_every_diagram_of_the_course_project_is_there(written: dict) -> None:
    """Shishkov (2014), "Graphs of the dynamic calculation", and the rest of the project."""
    names = {Path(p).stem for p in written["figures"]}
    assert names >= {
        "kinematics",  # S, V, J
        "forces_pg_pj_psum",  # Pg, Pj, PΣ
        "forces_k_n_z",  # along the rod, N, Z
        "tangential",  # T, TΣ, TΣ mean
        "turning_moment",  # excess work
        "flywheel",
        "crank_pin_polar",
        "big_end_polar",
        "crank_pin_developed",
        "main_journal_polar",
        "main_bearing_polar",
        "crank_pin_wear",
        "running_torques",
        "balance_orders",
    }
    tables = {Path(p).stem for p in written["tables"]}
    assert tables >= {"crank_table", "tangential", "crank_pin_loads", "main_journal_loads", "balance_orders"}


def test_the_page_is_self_contained(written: dict, page: str) -> None:
    images = re.findall(r'<img src="([^"]*)"', page)
    assert len(images) == len(written["figures"])
    for src, path in zip(images, written["figures"]):
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1]) == Path(path).read_bytes(), path
    without_images = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]*", "", page)
    assert not HTTP.search(without_images), HTTP.search(without_images)
    assert "<link" not in page and "@import" not in page and "<script src" not in page
    links = re.findall(r'(?:src|href)="([^"]*)"', page)
    assert all(link.startswith(("#", "data:image/png;base64,")) for link in links), links
    assert page.count("<script>") == 1


def test_the_page_cites_its_sources_and_says_where_each_figure_is(written: dict, page: str) -> None:
    for words in ("Shishkov", "Dinamika dvigatelei", "Kolchin", "Demidov", "Popyk"):
        assert words in page
    text = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]*", "", page)  # base64 may spell anything
    assert "seed" not in text.lower()
    for path in written["figures"]:
        assert f"figures/{Path(path).name}" in page
    for path in written["tables"]:
        assert f"tables/{Path(path).name}" in page
    for heading in ("Piston kinematics", "Forces of the crank mechanism", "Bearing loads", "Balance", "Sources"):
        assert f">{heading} <span" in page or f">{heading}</h" in page, heading


def test_the_tables_are_the_librarys_numbers(written: dict, engine: rotor.Engine) -> None:
    tables = {Path(p).stem: p for p in written["tables"]}
    table = read_csv(tables["crank_table"])
    ref = rotor.crank_table(engine, step_deg=STEP, kinematics="exact")
    assert list(table) == list(ref.columns)
    for name, values in table.items():
        np.testing.assert_allclose(values, ref.columns[name], rtol=1e-9, atol=1e-9, err_msg=name)

    tang = read_csv(tables["tangential"])
    R = float(engine.geometry.crank_radius_m)
    t_sum = sum(tang[f"t{c}_N"] for c in range(1, 5))
    np.testing.assert_allclose(t_sum, tang["t_sum_N"], rtol=1e-8, atol=1e-6)
    np.testing.assert_allclose(tang["m_sum_Nm"], tang["t_sum_N"] * R, rtol=1e-9)
    np.testing.assert_allclose(tang["t1_N"], table["t_N"], rtol=1e-8, atol=1e-6)  # cylinder 1 is the table's

    pins = read_csv(tables["crank_pin_loads"])
    assert np.allclose(np.diff(pins["angle_deg"]), STEP)
    np.testing.assert_allclose(pins["q1_N"], np.hypot(pins["t1_N"], pins["z1_1_N"]), rtol=1e-9)

    orders = read_csv(tables["balance_orders"])
    ref_orders = rotor.balance(engine).to_json_dict()["orders"]
    np.testing.assert_allclose(orders["free_force_N"], [o["free_force_N"] for o in ref_orders], rtol=1e-9, atol=1e-6)
    fly = read_csv(tables["flywheel"])
    assert fly["delta"][0] == 0.01 and 1100 < fly["excess_work_J"][0] < 1300  # 1194 J: the preset's comment


def test_the_turning_moment_diagram_has_the_flywheels_excess_work(written: dict, page: str) -> None:
    fly = read_csv(next(p for p in written["tables"] if p.endswith("flywheel.csv")))
    shown = float(re.search(r"swings by the excess work .*?: ([\d.]+) J on this diagram", page).group(1))
    assert shown == pytest.approx(fly["excess_work_J"][0], rel=2e-3)


def test_a_failed_report_leaves_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, engine: rotor.Engine) -> None:
    def broken(*args: object, **kwargs: object) -> None:
        raise RuntimeError("the disk caught fire")

    monkeypatch.setattr("rotor.design.report.save_figure", broken)
    with pytest.raises(RuntimeError, match="caught fire"):
        rotor.report(engine, tmp_path / "new" / "r", step_deg=STEP)
    assert os.listdir(tmp_path) == []  # the folder made for it is gone too
    old = tmp_path / "old"  # a previous report stays as it was
    previous_report(old, {"a.png": b"png"})
    before = {p.relative_to(old).as_posix(): p.read_bytes() for p in old.rglob("*") if p.is_file()}
    with pytest.raises(RuntimeError, match="caught fire"):
        rotor.report(engine, old, step_deg=STEP)
    assert {p.relative_to(old).as_posix(): p.read_bytes() for p in old.rglob("*") if p.is_file()} == before
    assert sorted(os.listdir(old)) == [".rotor-report.json", "figures", "index.html", "tables"]


def test_bad_arguments_are_refused_before_anything_is_written(tmp_path: Path, engine: rotor.Engine) -> None:
    with pytest.raises(rotor.EngineError, match="must divide"):
        rotor.report(engine, tmp_path / "r", step_deg=7.0)
    with pytest.raises(rotor.EngineError, match="delta"):
        rotor.report(engine, tmp_path / "r", delta=1.5)
    with pytest.raises(rotor.EngineError, match="kinematics"):
        rotor.report(engine, tmp_path / "r", kinematics="approximate")
    with pytest.raises(TypeError, match="out_dir"):
        rotor.report(engine, b"r")  # type: ignore[arg-type]
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "thesis.tex").write_text("mine\n")
    with pytest.raises(FileExistsError, match="holds other files"):
        rotor.report(engine, tmp_path / "other")
    assert sorted(os.listdir(tmp_path)) == ["other"]
    assert os.listdir(tmp_path / "other") == ["thesis.tex"]


def test_the_report_object_says_what_it_wrote() -> None:
    r = rotor.Report("E", 1250.0, 10.0, 1.0, 0.01, "exact", "out", ("a.png",), ("t.csv",), 3.2)
    assert r.page == os.path.join("out", "index.html")
    assert r.paths() == [r.page, os.path.join("out", "figures", "a.png"), os.path.join("out", "tables", "t.csv")]
    assert "out/index.html" in r.summary() and "1 figures" in r.summary()
    assert json.loads(json.dumps(r.to_json_dict()))["figures"] == [os.path.join("out", "figures", "a.png")]
    assert repr(r) == "<Report: E at 1250 rpm in out>"


def test_loads_and_balance_commands(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    rc, text, _ = run_cli(capsys, "balance", "4chn15", "--orders", "4", "--json", "--plot", str(tmp_path / "b"))
    assert rc == 0
    data = json.loads(text)
    assert [o["order"] for o in data["orders"]] == [1, 2, 3, 4]
    assert set(data["orders"][0]) >= {"order", "free_force_N", "free_moment_Nm"}
    assert data["plots"] == [str(tmp_path / "b" / "balance.png")]
    rc, text, _ = run_cli(capsys, "balance", "4chn15")
    assert rc == 0 and "free force" in text

    rc, text, _ = run_cli(capsys, "loads", "4chn15", "--step", "10", "--plot", str(tmp_path / "l"))
    assert rc == 0 and "crank pins" in text
    assert sorted(os.listdir(tmp_path / "l")) == sorted(
        [
            "crank_pin_polar.png",
            "big_end_polar.png",
            "crank_pin_developed.png",
            "main_journal_polar.png",
            "main_bearing_polar.png",
            "crank_pin_wear.png",
            "main_journal_wear.png",
            "running_torques.png",
        ]
    )
    rc, text, _ = run_cli(capsys, "loads", "4chn15", "--step", "10", "--json")
    assert rc == 0 and json.loads(text)["step_deg"] == 10.0


# ----------------------------------------------------------------------------- the browser
BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def _browser() -> str | None:
    return next((path for name in BROWSERS if (path := shutil.which(name))), None)


def test_every_figure_renders_in_a_headless_browser(written: dict) -> None:
    """The page opened in headless Chromium: its inline script counts the images that the
    browser decoded (``complete`` and ``naturalWidth > 0``) into the DOM, which is dumped."""
    browser = _browser()
    if browser is None:
        pytest.skip("no headless browser: install Debian's `chromium` package (`.ci/run` does) to check the page")
    with tempfile.TemporaryDirectory(prefix="rotor-chromium-") as profile:
        run = subprocess.run(
            [
                browser,
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--no-first-run",
                f"--user-data-dir={profile}",
                "--virtual-time-budget=10000",
                "--dump-dom",
                Path(written["page"]).resolve().as_uri(),
            ],
            capture_output=True,
            text=True,
            timeout=180,
        )
    assert run.returncode == 0, run.stderr[-2000:]
    found = re.search(r'<p id="render-check" data-figures="(\d+)" data-rendered="(\d*)"', run.stdout)
    assert found, "the page's check did not run:\n" + run.stdout[-1000:]
    figures, rendered = int(found.group(1)), found.group(2)
    assert figures == len(written["figures"])
    assert rendered == str(figures), f"{rendered or 'no'} of {figures} figures rendered"


def _files(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` (its links as where they point): relative path: bytes."""
    out: dict[str, bytes] = {}
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(folder).as_posix()
        if p.is_symlink():
            out[rel] = b"-> " + os.fsencode(os.readlink(p))
        elif p.is_file():
            out[rel] = p.read_bytes()
        else:
            out[rel + "/"] = b""
    return out


def _users_photo(out: Path) -> str:
    previous_report(out)
    (out / "figures" / "holiday.jpg").write_bytes(b"\xff\xd8 a photo")
    return "figures/holiday.jpg"


def _users_page(out: Path) -> str:
    out.mkdir()
    (out / "index.html").write_text("<h1>my own page</h1>\n")
    return "index.html"


def _page_replaced(out: Path) -> str:
    previous_report(out)
    (out / "index.html").write_text("<h1>my own page</h1>\n")
    return "index.html, changed since the report wrote it"


def _users_subfolder(out: Path) -> str:
    previous_report(out)
    (out / "tables" / "mine").mkdir()
    (out / "tables" / "mine" / "notes.csv").write_text("x\n")
    return "tables/mine/"


def _link_in_figures(out: Path) -> str:
    previous_report(out)
    (out / "figures" / "elsewhere.png").symlink_to(out.parent / "elsewhere.png")
    return "figures/elsewhere.png"


def _no_record(out: Path) -> str:
    (out / "figures").mkdir(parents=True)
    (out / "figures" / "plot.png").write_bytes(b"png")
    (out / "index.html").write_text("<p>a report</p>\n")
    return "figures/plot.png"


@pytest.mark.parametrize(
    "make",
    [_users_photo, _users_page, _page_replaced, _users_subfolder, _link_in_figures, _no_record],
    ids=["a photo in figures", "the user's page", "a page replaced", "a subfolder", "a link", "no record"],
)
def test_a_folder_holding_what_the_report_did_not_write_is_refused_and_kept(
    make, tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "d"
    shown = make(out)
    before = _files(out)
    monkeypatch.setattr("rotor.design.report.crank_table", lambda *a, **k: pytest.fail("the work started"))
    rc, _, err = run_cli(capsys, "report", "4chn15", "--out", out)
    assert rc == 2 and err.count("\n") == 1, err
    assert err.startswith(f"rotor: error: {out}: holds other files (") and shown in err, err
    assert "give an empty or new folder" in err
    assert _files(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d"]


def test_a_swap_stopped_halfway_puts_the_previous_report_back(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from rotor.design.report import report_folder

    out = tmp_path / "r"
    previous_report(out, {"a.png": b"old"})
    before = _files(out)
    page = os.path.join(os.path.realpath(out), "index.html")
    real_rename = os.rename
    halfway = tmp_path / "halfway"

    def stop_at_the_new_page(src, dst):
        if os.fspath(dst) == page and not halfway.exists():  # the new page about to go in place
            shutil.copytree(out, halfway, symlinks=True)  # what a run killed here would leave
            raise KeyboardInterrupt
        real_rename(src, dst)

    monkeypatch.setattr(os, "rename", stop_at_the_new_page)
    with pytest.raises(KeyboardInterrupt):
        with report_folder(str(out)) as tmp:
            os.mkdir(os.path.join(tmp, "figures"))
            os.mkdir(os.path.join(tmp, "tables"))
            Path(tmp, "figures", "b.png").write_bytes(b"new")
            Path(tmp, "index.html").write_text("<p>new</p>\n")
    monkeypatch.undo()
    assert _files(out) == before  # the previous report whole, no temporary folder left
    # the folder as a run killed halfway leaves it is still a report's: the next one replaces it
    assert "figures/b.png" in _files(halfway) and "index.html" not in _files(halfway)
    previous_report(halfway)
    assert [n for n in _files(halfway) if not n.startswith(".rotor-report-")] == [
        ".rotor-report.json",
        "figures/",
        "figures/old.png",
        "index.html",
        "tables/",
        "tables/old.csv",
    ]

"""HTML report in a real browser: headless Chromium opens the page from disk.

Checks: no JavaScript error, no request to any other host, every plot drawn (plotly adds an
``svg.main-svg``), and a screenshot saved to ``test-artifacts/report-screenshot.png``.

The page records its own errors (``window.__errors``, installed first thing in <head>) and, once
every ``Plotly.newPlot`` promise has settled, writes them with the number of drawn plots into
``<div id="render-status" data-errors=.. data-plots=.. data-expected=.. data-done=1>``, which
``chromium --dump-dom`` exposes. Network requests are read from Chromium's net log
(``--log-net-log``); requests the page makes carry a ``file://`` network isolation key, unlike
the browser's own background requests. All host names resolve to nothing
(``--host-resolver-rules``), so no test ever reaches the network.

Needs the Debian package ``chromium`` (``.ci/run`` installs it). Skipped when it is missing,
except under ``CI=true`` where a missing browser is a failure.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from report_fixtures import write_run  # noqa: E402

from ngtmc import report  # noqa: E402

pytestmark = pytest.mark.browser

REPO = Path(__file__).resolve().parents[1]
ARTIFACTS = REPO / "test-artifacts"


def _chromium() -> str | None:
    for cand in (shutil.which("chromium"), "/usr/bin/chromium"):
        if cand and Path(cand).is_file() and os.access(cand, os.X_OK):
            return cand
    return None


@pytest.fixture(scope="module")
def chromium():
    exe = _chromium()
    if exe is None:
        if os.environ.get("CI") == "true":
            pytest.fail("CI=true but no chromium binary found (install the Debian package "
                        "'chromium'; .ci/run does this)")
        pytest.skip("no chromium binary found (shutil.which('chromium') or /usr/bin/chromium); "
                    "install the Debian package 'chromium' to run the browser tests")
    return exe


def _run_chromium(exe: str, page: Path, tmp: Path, *extra: str, timeout: int = 180):
    profile = tmp / f"profile-{len(list(tmp.glob('profile-*')))}"
    profile.mkdir(parents=True)
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", "--disable-default-apps", "--disable-extensions",
           "--hide-scrollbars", "--mute-audio", f"--user-data-dir={profile}",
           "--host-resolver-rules=MAP * ~NOTFOUND", "--enable-logging=stderr", "--v=0",
           "--virtual-time-budget=10000", *extra, page.resolve().as_uri()]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    return proc


def _page_requests(netlog: Path) -> list[str]:
    """URLs of http(s) requests started on behalf of a file:// page (not browser internals)."""
    text = netlog.read_text(encoding="utf-8", errors="replace").rstrip()
    try:
        log = json.loads(text)
    except json.JSONDecodeError:  # log cut short when the browser exits: close it
        try:
            log = json.loads(text.rstrip(",") + "]}")
        except json.JSONDecodeError:  # cut inside an event: drop the partial event
            log = json.loads(text[:text.rindex("},")] + "}]}")
    types = {v: k for k, v in log["constants"]["logEventTypes"].items()}
    urls = []
    for ev in log.get("events", []):
        if types.get(ev.get("type")) != "URL_REQUEST_START_JOB":
            continue
        p = ev.get("params") or {}
        url = str(p.get("url", ""))
        from_page = ("file://" in str(p.get("network_isolation_key", ""))
                     or p.get("initiator") not in (None, "not an origin"))
        if from_page and re.match(r"(?i)(https?|wss?|ftp)://", url):
            urls.append(url)
    return urls


class _PlotFinder(HTMLParser):
    """Collects, for every element with class "plot", whether an svg.main-svg is inside it."""

    VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta",
            "param", "source", "track", "wbr"}

    def __init__(self):
        super().__init__()
        self.stack: list[tuple[str, str | None]] = []  # (tag, plot id if a plot container)
        self.plots: dict[str, bool] = {}
        self.status: dict[str, str] = {}

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        classes = (a.get("class") or "").split()
        if a.get("id") == "render-status":
            self.status = {k: v or "" for k, v in a.items()}
        if "main-svg" in classes:
            for _, pid in self.stack:
                if pid:
                    self.plots[pid] = True
        if tag in self.VOID:
            return
        pid = None
        if "plot" in classes and tag == "div":
            pid = a.get("id") or f"plot-{len(self.plots)}"
            self.plots.setdefault(pid, False)
        self.stack.append((tag, pid))

    def handle_startendtag(self, tag, attrs):
        a = dict(attrs)
        if "main-svg" in (a.get("class") or "").split():
            for _, pid in self.stack:
                if pid:
                    self.plots[pid] = True

    def handle_endtag(self, tag):
        for i in range(len(self.stack) - 1, -1, -1):
            if self.stack[i][0] == tag:
                del self.stack[i:]
                break


class _LinkFinder(HTMLParser):
    """src/href/srcset/action/data attributes of elements that point to another host."""

    def __init__(self):
        super().__init__()
        self.found: list[str] = []

    def handle_starttag(self, tag, attrs):
        for k, v in attrs:
            if k in ("src", "href", "srcset", "action", "data", "poster", "xlink:href") and v:
                if re.match(r"(?i)\s*((https?|wss?|ftp):)?//", v):
                    self.found.append(f"<{tag} {k}={v}>")

    handle_startendtag = handle_starttag


def _outside_links(html_text: str) -> list[str]:
    f = _LinkFinder()
    f.feed(html_text)
    return f.found


def _check_page(exe: str, page: Path, tmp: Path, min_plots: int) -> dict:
    netlog = tmp / f"netlog-{page.stem}.json"
    proc = _run_chromium(exe, page, tmp, f"--log-net-log={netlog}", "--dump-dom")
    assert proc.returncode == 0, proc.stderr[-3000:]
    dom = proc.stdout
    finder = _PlotFinder()
    finder.feed(dom)
    st = finder.status
    assert st, "render-status marker missing from the rendered DOM"
    assert st.get("data-done") == "1", f"rendering did not finish: {st}"
    assert st.get("data-errors") == "0", f"JavaScript errors: {st.get('data-error-text')}"
    uncaught = [ln for ln in proc.stderr.splitlines() if "CONSOLE" in ln and "Uncaught" in ln]
    assert not uncaught, uncaught
    assert len(finder.plots) >= min_plots, finder.plots
    missing = [pid for pid, drawn in finder.plots.items() if not drawn]
    assert not missing, f"plots not rendered: {missing}"
    assert int(st["data-plots"]) == int(st["data-expected"]) == len(finder.plots), st
    # no request to any other host: element attributes in the file and in the rendered DOM,
    # and the requests in the net log
    assert _outside_links(page.read_text(encoding="utf-8")) == []
    assert _outside_links(dom) == []
    assert netlog.is_file(), "chromium wrote no net log"
    assert _page_requests(netlog) == []
    return st


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    root = tmp_path_factory.mktemp("browser")
    reports = root / "reports"
    tpb = write_run(reports / "three_point_bending_quick")
    cg = write_run(reports / "contact_gamma0_quick", study="contact_gamma0")
    fine = write_run(reports / "three_point_bending_fine", cases=[("main", "main", 1e-3, {})],
                     n_elements=4000, wall_time_s=600.0)
    pages = {"tpb": report.render_report(tpb), "cg": report.render_report(cg),
             "fine": report.render_report(fine)}
    pages["index"] = report.render_index(reports)
    return root, pages


def test_report_renders_in_chromium(chromium, rendered, tmp_path):
    _, pages = rendered
    st = _check_page(chromium, pages["tpb"], tmp_path, min_plots=9)
    assert int(st["data-plots"]) >= 9  # 6 curves, 2 snapshot sliders, 1 shared mesh


def test_contact_gamma0_report_renders_in_chromium(chromium, rendered, tmp_path):
    _, pages = rendered
    # no phase field in this study: no W_f/alpha plot and no Gc(rho) plot (tests/test_report_fit.py)
    _check_page(chromium, pages["cg"], tmp_path, min_plots=11)


def test_index_renders_in_chromium(chromium, rendered, tmp_path):
    _, pages = rendered
    _check_page(chromium, pages["index"], tmp_path, min_plots=1)


def test_screenshot(chromium, rendered, tmp_path):
    _, pages = rendered
    ARTIFACTS.mkdir(exist_ok=True)
    shots = {"report-screenshot.png": (pages["tpb"], "1400,3000"),
             "report-screenshot-full.png": (pages["tpb"], "1400,8000"),
             "report-contact-gamma0-screenshot.png": (pages["cg"], "1400,9000"),
             "index-screenshot.png": (pages["index"], "1400,1600")}
    for name, (page, size) in shots.items():
        out = ARTIFACTS / name
        if out.exists():
            out.unlink()
        proc = _run_chromium(chromium, page, tmp_path, f"--screenshot={out}",
                             f"--window-size={size}")
        assert proc.returncode == 0, proc.stderr[-3000:]
        assert out.is_file() and out.stat().st_size > 20_000, name
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_checks_catch_a_bad_page(chromium, tmp_path):
    """The checks above must be able to fail: a page with an error and an outside request."""
    bad = tmp_path / "bad.html"
    bad.write_text(
        "<!DOCTYPE html><html><head><script>window.__errors=[];"
        "window.addEventListener('error', e => window.__errors.push(String(e.message)));</script>"
        "</head><body><img src='https://example.invalid/x.png'>"
        "<div id='render-status' data-done='0'></div><script>"
        "setTimeout(function(){var s=document.getElementById('render-status');"
        "s.setAttribute('data-errors', String(window.__errors.length));"
        "s.setAttribute('data-done','1');}, 10);"
        "fetch('http://example.invalid/y').catch(function(){}); undefinedFunction();"
        "</script></body></html>", encoding="utf-8")
    netlog = tmp_path / "bad-netlog.json"
    proc = _run_chromium(chromium, bad, tmp_path, f"--log-net-log={netlog}", "--dump-dom")
    assert proc.returncode == 0
    finder = _PlotFinder()
    finder.feed(proc.stdout)
    assert finder.status.get("data-errors") == "1"
    reqs = _page_requests(netlog)
    assert any("example.invalid" in u for u in reqs), reqs


PROBE = """<script>
(function wait() {
  var st = document.getElementById("render-status");
  if (st.getAttribute("data-done") !== "1") { return setTimeout(wait, 50); }
  var el = document.getElementById("snap-0"), out = [];
  function vis() {
    return el.data.map(function (t, i) { return t.visible === false ? null : i; })
                  .filter(function (i) { return i !== null; }).join(",");
  }
  out.push(vis());
  el.emit("plotly_sliderchange", {step: {value: "0"}});
  setTimeout(function () {
    out.push(vis());
    el.emit("plotly_buttonclicked", {button: {label: "true scale × 1"}});
    setTimeout(function () {
      out.push(vis());
      var d = document.createElement("div");
      d.id = "probe"; d.setAttribute("data-out", out.join(";"));
      d.setAttribute("data-title", el.layout.title.text);
      d.setAttribute("data-errors", String(window.__errors.length));
      document.body.appendChild(d);
    }, 300);
  }, 300);
})();
</script></body>"""


def test_snapshot_slider_and_scale_toggle(chromium, tmp_path):
    """Moving the slider shows another frame; the scale buttons switch to the true scale."""
    import numpy as np
    run = write_run(tmp_path / "inter", cases=[("main", "main", 2e-3, {})])
    z = dict(np.load(run / "snapshots.npz"))
    z["main__u"] = z["main__u"] * 0.05  # small displacements: drawn magnified
    np.savez(run / "snapshots.npz", **z)
    page = report.render_report(run)
    probe = tmp_path / "probe.html"
    probe.write_text(page.read_text(encoding="utf-8").replace("</body>", PROBE), encoding="utf-8")
    proc = _run_chromium(chromium, probe, tmp_path, "--dump-dom")
    assert proc.returncode == 0
    m = re.search(r'<div id="probe" data-out="([^"]*)" data-title="([^"]*)" data-errors="(\d+)"',
                  proc.stdout)
    assert m, "interaction probe did not run"
    start, frame0, true_scale = (set(x.split(",")) for x in m.group(1).split(";"))
    assert start != frame0 != true_scale and start != true_scale
    assert "true scale" in m.group(2)
    assert m.group(3) == "0"

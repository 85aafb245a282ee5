"""`dvc plots show` opens without internet (issue 31 item 3).

DVC's page loads Vega from a CDN, so offline it was blank. tools/plots_template.py writes .dvc/plots.html, a template
with Vega, Vega-Lite and Vega-Embed inlined from vl-convert-python, and .dvc/config points DVC at it. Each test here
makes a DVC project in tmp_path with the project's plot definitions (dvc.yaml's `plots:`), series
(reports/plots/*.csv, committed) and .dvc/config, writes the template with the tool and runs `dvc plots show` as the
README says. The page must load nothing from the network, and its Vega-Lite specs must render (vl-convert executes
them offline, as the page's own libraries would). The last test opens the page in headless Chromium with the network
blocked and looks at what it draws (its screenshot was looked at: four charts, bars and lines drawn); `make test`
installs Debian's chromium first when run as root (as it installs poppler-utils), so it runs wherever CI runs; it is
skipped only where no Chromium is installed and none could be (not root: `apt-get install chromium` to run it).
"""

import html
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import vl_convert
import yaml

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent

_spec = importlib.util.spec_from_file_location("plots_template", ROOT / "tools" / "plots_template.py")
plots_template = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(plots_template)

CHROMIUM = next(
    (p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")) if p), None
)


def run(project, *args):
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}", "DVC_NO_ANALYTICS": "1"}
    result = subprocess.run(args, cwd=project, env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, f"{' '.join(map(str, args))}:\n{result.stdout}\n{result.stderr}"
    return result


def definitions():
    """dvc.yaml's plot definitions, by file."""
    return {
        path: props
        for entry in yaml.safe_load((ROOT / "dvc.yaml").read_text())["plots"]
        for path, props in entry.items()
    }


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    """A DVC project with this one's plots and .dvc/config, the template written by the tool: as after `make plots`."""
    project = tmp_path_factory.mktemp("plots")
    run(project, str(BIN / "dvc"), "init", "--no-scm", "--quiet")
    shutil.copy2(ROOT / ".dvc" / "config", project / ".dvc" / "config")
    (project / "dvc.yaml").write_text(yaml.safe_dump({"plots": [{p: d} for p, d in definitions().items()]}))
    for path in definitions():
        (project / path).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / path, project / path)
    plots_template.write(project / ".dvc" / "plots.html")
    return project


@pytest.fixture(scope="module")
def page(project):
    """`dvc plots show`'s page, as the README runs it (no option: .dvc/config names the template)."""
    out = run(project, str(BIN / "dvc"), "plots", "show")
    assert "index.html" in out.stdout
    return project / "dvc_plots" / "index.html"


class Resources(HTMLParser):
    """Every URL the page would load: script, link, img, iframe, source, object and CSS url()."""

    def __init__(self):
        super().__init__()
        self.urls, self.inline_scripts, self.in_style = [], 0, False

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        for name in ("src", "href", "data", "srcset"):
            if attrs.get(name) and tag in ("script", "link", "img", "iframe", "source", "object", "embed"):
                self.urls.append(attrs[name])
        if tag == "script" and not attrs.get("src"):
            self.inline_scripts += 1
        self.in_style = tag == "style"

    def handle_endtag(self, tag):
        self.in_style = False

    def handle_data(self, data):
        if self.in_style:
            self.urls += re.findall(r"url\(\s*['\"]?([^'\")]+)", data)


def specs(page):
    """The Vega-Lite spec of each plot div, as DVC writes it: `var spec = {...}; vegaEmbed('#id', spec);`."""
    return [json.loads(s) for s in re.findall(r"var spec = (.*?);\s*vegaEmbed\(", page, re.S)]


def test_dvc_config_points_dvc_plots_show_at_the_template_the_tool_writes_and_git_ignores_it():
    config = (ROOT / ".dvc" / "config").read_text()
    assert re.search(r"^\[plots\]\s*\n\s*html_template = plots.html$", config, re.M)  # relative to .dvc/
    assert plots_template.DEFAULT_OUT == ROOT / ".dvc" / "plots.html"
    assert "/.dvc/plots.html" in (ROOT / ".gitignore").read_text().splitlines()


def test_the_template_inlines_the_vega_libraries_and_keeps_dvcs_placeholders_but_not_the_cdn_scripts():
    text = plots_template.render()
    assert "{plot_divs}" in text and "{refresh_tag}" in text and "{scripts}" not in text
    assert "window.vegaEmbed=" in text and "window.vegaLite=" in text and "window.vega=" in text
    assert text.lower().count("</script") == 1  # the bundle cannot end its own script early
    versions = plots_template.versions()
    assert versions["vega-lite"].split(".")[0] == "5" and versions["vega-lite"] in vl_convert.get_vegalite_versions()
    assert f"vl-convert-python {versions['vl-convert-python']}" in text


def test_dvc_plots_show_writes_a_page_that_loads_nothing_from_the_network(page):
    text = page.read_text(encoding="utf-8")
    found = Resources()
    found.feed(text)
    assert found.urls == []  # not even a relative one: the page is one file
    assert found.inline_scripts == 1 + len(definitions())  # the libraries, then one call per plot
    assert "cdn.jsdelivr.net" not in text and "<script src" not in text
    assert len(text) > 500_000  # the bundle is there


def marks(svg, kind):
    """The mark paths of one kind ("rect", "line") in an SVG drawn by Vega, with what each says it shows."""
    groups = re.findall(rf'<g class="mark-{kind} role-mark[^"]*"[^>]*>(.*?)</g>', svg, re.S)
    paths = [re.findall(r'\b(aria-label|d)="([^"]*)"', tag) for g in groups for tag in re.findall(r"<path\b[^>]*>", g)]
    return [(dict(attrs).get("aria-label", ""), dict(attrs).get("d", "")) for attrs in paths]


def check_drawn(svg, title):
    """The plot titled `title` has one bar per row, or one line through every row per column of its series."""
    path, props = next((p, d) for p, d in definitions().items() if d["title"] == title)
    rows = len(pd.read_csv(ROOT / path))
    if props.get("template") == "bar_horizontal":
        assert len(marks(svg, "rect")) == rows, title
    else:
        series = props["y"] if isinstance(props["y"], list) else [props["y"]]
        lines = {
            re.search(r"field: (\w+)", label).group(1) for label, d in marks(svg, "line") if d.count("L") == rows - 1
        }
        assert lines == set(series), title


def test_every_plot_on_the_page_renders_offline_with_one_mark_per_row_and_series(page):
    """vl-convert runs the page's specs through Vega-Lite 5 and Vega, as the browser does, and draws them to SVG."""
    drawn = specs(page.read_text(encoding="utf-8"))
    titles = [s["title"]["text"] if isinstance(s["title"], dict) else s["title"] for s in drawn]
    assert sorted(titles) == sorted(d["title"] for d in definitions().values())
    for spec, title in zip(drawn, titles, strict=True):
        assert spec["$schema"].endswith("/vega-lite/v5.json")
        check_drawn(vl_convert.vegalite_to_svg(spec, vl_version=plots_template.VEGA_LITE), title)


def purple_pixels(png):
    """Pixels in the hue of DVC's first series colour, #945dd6 (bars and lines; the page's text is grey)."""
    from matplotlib.colors import rgb_to_hsv
    from PIL import Image

    hue = rgb_to_hsv([0x94 / 255, 0x5D / 255, 0xD6 / 255])[0]
    h, s, v = np.moveaxis(rgb_to_hsv(np.asarray(Image.open(png).convert("RGB")) / 255), -1, 0)
    return int(np.count_nonzero((s > 0.3) & (v > 0.3) & (np.abs(h - hue) < 0.04)))


def chromium(page, tmp_path, *args):
    """Open `page` in headless Chromium with every network request refused; the console's messages."""
    command = [
        CHROMIUM, "--headless", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
        f"--user-data-dir={tmp_path / 'profile'}",
        "--proxy-server=127.0.0.1:9", "--host-resolver-rules=MAP * ~NOTFOUND",  # no network: a refused proxy, no DNS
        "--enable-logging=stderr", "--v=0", "--virtual-time-budget=15000", "--window-size=1000,2000",
        *args, page.as_uri(),
    ]  # fmt: skip
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        command.insert(1, "--no-sandbox")  # Chromium's sandbox refuses to run as root
    result = subprocess.run(command, capture_output=True, text=True, timeout=180)
    assert result.returncode == 0, result.stderr
    return result.stdout, [line for line in result.stderr.splitlines() if ":CONSOLE" in line]


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium to render the page in (apt-get install chromium)")
def test_the_page_draws_every_plot_in_headless_chromium_with_the_network_blocked(project, page, tmp_path):
    dom, console = chromium(page, tmp_path, "--dump-dom")
    assert not [line for line in console if "Uncaught" in line or "Error" in line], console
    # vega-embed has drawn each plot (this Vega-Embed draws SVG): its bars or lines, one per row or series
    drawn = re.findall(r'<svg\b[^>]*class="marks".*?</svg>', dom, re.S)
    titles = [html.unescape(re.search(r"aria-label=\"Title text '(.*?)'\"", svg).group(1)) for svg in drawn]
    assert sorted(titles) == sorted(d["title"] for d in definitions().values()), dom[-3000:]
    for svg, title in zip(drawn, titles, strict=True):
        check_drawn(svg, title)
    shot = tmp_path / "offline.png"
    chromium(page, tmp_path, f"--screenshot={shot}")
    assert purple_pixels(shot) > 20_000  # the bars and lines, drawn

    # the control: DVC's own page (its CDN scripts) is blank under the same blocking, so the browser had no network
    from dvc_render.html import PAGE_HTML  # DVC's page when no template is configured

    default = project / "default.html"
    default.write_text(PAGE_HTML)
    run(project, str(BIN / "dvc"), "plots", "show", "--html-template", str(default), "-o", "cdn")
    cdn_page = project / "cdn" / "index.html"
    assert "cdn.jsdelivr.net" in cdn_page.read_text(encoding="utf-8")
    _, console = chromium(cdn_page, tmp_path, f"--screenshot={tmp_path / 'cdn.png'}")
    assert any("vegaEmbed is not defined" in line for line in console), console
    assert purple_pixels(tmp_path / "cdn.png") == 0

"""Write the HTML template that lets ``dvc plots show`` open without internet (issue 31, item 3).

DVC's own page loads Vega, Vega-Lite and Vega-Embed from a CDN (``dvc_render.vega.VegaRenderer.SCRIPTS``), so offline
it is blank. This template has those libraries inlined instead, from the installed ``vl-convert-python`` package
(``vl_convert.javascript_bundle``: no download at run time, the version pinned in constraints.txt), and leaves out
DVC's ``{scripts}`` placeholder, which is where the CDN tags would go. ``.dvc/config`` points ``plots.html_template``
at the default output, ``.dvc/plots.html`` (ignored by git: about 0.9 MB of generated JavaScript), so
``dvc plots show`` uses it; ``make plots`` writes it and runs that, and ``make test`` and ``make repro`` write it too.

``python tools/plots_template.py [OUT]`` writes OUT (default ``.dvc/plots.html``) and prints the versions it inlined.
A page from this template renders only Vega plots, the only kind dvc.yaml declares (a Plotly renderer's script would
be dropped with the placeholder).
"""

from __future__ import annotations

import argparse
import html
import os
import sys
import tempfile
from importlib.metadata import version
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUT = ROOT / ".dvc" / "plots.html"

VEGA_LITE = "5.21"
"""Vega-Lite major version 5, as the ``$schema`` of every spec DVC's templates write (``vega-lite/v5.json``); 5.21 is
the last 5.x that vl-convert bundles. Its Vega and Vega-Embed are the ones vl-convert ships (Vega 6, Vega-Embed 7),
which read the Vega 5 specs Vega-Lite 5 compiles to."""

# DVC's placeholders (dvc_render.html.HTML): {plot_divs} and {refresh_tag} are kept; {scripts} is left out
PLACEHOLDERS = ("{plot_divs}", "{refresh_tag}", "{scripts}")

PAGE = """<!DOCTYPE html>
<html>
<head>
    <meta charset="utf-8">
    {refresh_tag}
    <title>DVC Plot</title>
    <!-- {provenance}: written by tools/plots_template.py; no script is loaded from the network -->
    <script>
(function () {{
"use strict";
{bundle}
}})();
    </script>
    <style>
        table {{
            border-spacing: 15px;
        }}
    </style>
</head>
<body>
    {plot_divs}
</body>
</html>
"""


def versions() -> dict[str, str]:
    """The versions of what the template inlines."""
    import vl_convert

    return {
        "vl-convert-python": version("vl-convert-python"),
        "vega": vl_convert.get_vega_version(),
        "vega-lite": VEGA_LITE,
        "vega-embed": vl_convert.get_vega_embed_version(),
    }


def render() -> str:
    """The template's text: DVC's page layout with the Vega libraries inlined in one classic script."""
    import vl_convert

    # the bundle ends by setting window.vegaEmbed, window.vega and window.vegaLite: the globals DVC's plot divs call.
    # Wrapped in a function so that its top-level names stay out of the page's scope (DVC's divs declare `var spec`).
    bundle = vl_convert.javascript_bundle(vl_version=VEGA_LITE)
    for bad in (*PLACEHOLDERS, "</script"):
        # DVC fills the template by plain text replacement, and the HTML parser ends the script at `</script`
        if bad in bundle.lower():
            raise RuntimeError(f"vl-convert's bundle contains {bad!r}: it cannot be inlined as it is")
    provenance = html.escape(", ".join(f"{name} {v}" for name, v in versions().items()))
    page = PAGE.format(bundle=bundle, provenance=provenance, refresh_tag="{refresh_tag}", plot_divs="{plot_divs}")
    assert "{plot_divs}" in page and "{scripts}" not in page
    return page


def write(out: Path) -> Path:
    """Write the template to ``out`` (under a temporary name, then renamed: never half a file)."""
    out.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(render())
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", type=Path, default=DEFAULT_OUT, help="default: .dvc/plots.html")
    args = parser.parse_args(argv)
    out = write(args.out)
    inlined = ", ".join(f"{name} {v}" for name, v in versions().items())
    print(f"{out}: the offline template for `dvc plots show` ({inlined})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

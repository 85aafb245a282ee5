"""DVC stage ``figure2``: the reference's Figure 2 -> reports/figures/figure2.{png,pdf}."""

from __future__ import annotations

from pathlib import Path

from bogie.plotting import figure2, save_figure
from pipeline.config import load_params


def main() -> None:
    params = load_params().get("figure2", {})
    fig = figure2(
        q_max=float(params.get("q_max", 20.0)),
        slopes_deg=tuple(float(s) for s in params.get("slopes_deg", (0.0, 0.5, 1.0, 1.5, 2.0))),
        chassis_deflection=float(params.get("chassis_deflection_mm", 57.0)) / 1e3,
    )
    out = Path("reports/figures")
    for suffix in ("png", "pdf"):
        save_figure(fig, out / f"figure2.{suffix}")


if __name__ == "__main__":
    main()

"""How a simulated scene looks: :class:`RenderStyle` and each scene's :func:`default_style`."""

from __future__ import annotations

from dataclasses import dataclass

from mvtrack.sim.scene import Scene


@dataclass(frozen=True)
class RenderStyle:
    """How a scene looks.

    Attributes
    ----------
    background : {"flat", "intersection", "plaza", "asphalt"}
        Background layout.
    ground : (int, int, int)
        Base BGR colour of the background (the road for ``flat`` and ``asphalt``).
    texture : float
        Amplitude (grey levels) of the background texture; 0 for a flat colour.
    noise_sigma : float
        Standard deviation of the per-frame sensor noise, grey levels (0: none).
    jitter : float
        Camera jitter: each frame's picture is translated by an independent uniform shift in
        ``[-jitter, jitter]`` px per axis (bilinear, sub-pixel: a shaking camera does not move
        in whole pixels).
    """

    background: str = "asphalt"
    ground: tuple[int, int, int] = (88, 88, 88)
    texture: float = 6.0
    noise_sigma: float = 2.0
    jitter: float = 0.0

    def __post_init__(self) -> None:
        if self.background not in ("flat", "intersection", "plaza", "asphalt"):
            raise ValueError(f"unknown background {self.background!r}")
        if self.noise_sigma < 0 or self.texture < 0 or self.jitter < 0:
            raise ValueError("noise_sigma, texture and jitter must be >= 0")


def default_style(scene: Scene) -> RenderStyle:
    """The style of each scene: X4 exactly as SPEC X4 (flat grey, no noise); X5 with σ = 3
    noise and ±1 px jitter (SPEC X5); X8 on paving with σ = 2; others asphalt."""
    if scene.name == "x4":
        grey = tuple(int(c) for c in scene.meta.get("background", (96, 96, 96)))
        return RenderStyle("flat", grey, 0.0, 0.0, 0.0)  # type: ignore[arg-type]
    if scene.name == "x5":
        return RenderStyle("intersection", (88, 88, 88), 6.0, 3.0, 1.0)
    if scene.name == "x8":
        return RenderStyle("plaza", (112, 118, 122), 5.0, 2.0, 0)
    if scene.name == "crowd":
        return RenderStyle("asphalt", (88, 88, 88), 6.0, 0.0, 0)
    return RenderStyle()

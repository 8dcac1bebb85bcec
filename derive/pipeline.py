"""From a scene to its derivation: the symbolic model, its modes and the rendered module text.

Pure: nothing here writes files or imports the numeric side. Where a module is
written, cached or loaded is the application's business (:mod:`springchain._modules`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable

from .scene import Scene


@dataclass(frozen=True)
class Derivation:
    """A scene's symbolic model, its modes and the rendered module source.

    ``source`` is rendered on first use (``springchain modes`` never needs it).
    """

    scene: Scene
    model: object
    modes: object
    render: Callable[[], str] = field(repr=False, compare=False)

    @cached_property
    def source(self) -> str:
        """The generated module's text (rendered once, on first use)."""
        return self.render()


def derive(scene: Scene, bundled: bool = False) -> Derivation:
    """Build the model, its modes and the module text (SymPy is imported here).

    Parameters
    ----------
    scene : Scene
    bundled : bool
        Whether the scene ships with springchain (only changes the header's regenerate hint).
    """
    if scene.chain is not None:
        from .chain import ChainModel, chain_modes
        from .chain_codegen import render_chain_module

        model = ChainModel(scene)
        modes = chain_modes(model)
        return Derivation(scene, model, modes, lambda: render_chain_module(model, bundled=bundled))
    from .codegen import render_module
    from .model import Model
    from .modes import closed_form_modes

    model = Model(scene)
    modes = closed_form_modes(model)
    return Derivation(scene, model, modes, lambda: render_module(model, modes, bundled=bundled))


__all__ = ["Derivation", "derive"]

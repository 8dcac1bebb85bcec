"""Symbolic side of mode sensitivities: derivatives of the element values with respect to the scene's
parameters (:mod:`.elements`) and closed-form ∂ω²/∂p (:mod:`.closed_form`)."""

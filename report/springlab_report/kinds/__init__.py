"""The registry of experiment kinds: one module per kind, each with KIND (the
name in the settings file's "experiment"), TITLE, ABOUT (what theory says to
look for) and render(experiment, context) -> HTML. The page shows the kinds
in this order; adding a kind is one module and one line here."""

from . import (cloth_showcase, contact, convergence, damping_budget, energy, fluid, mode,
               motion, rigid, rotation, solver_error, spectral, stability, stability_region,
               step_energy, work_precision)

KINDS = {m.KIND: m for m in (
    motion,
    energy,
    stability,
    stability_region,
    spectral,
    convergence,
    work_precision,
    solver_error,
    damping_budget,
    contact,
    mode,
    rotation,
    rigid,
    fluid,
    cloth_showcase,
    step_energy,
)}

"""The two kinds of sweep and what differs between them, in one place: the built-in crane's
(gpme_study.spec, point, metrics: each point a rigid and a flexible run at the same
parameters and the flexible arm's vibration measured against its rigid twin) and a model
file's (gpme_study.model_spec, model_point, model_metrics: one run of the file, generic
metrics).  The runner, the command and the cost estimate ask the kind of a spec
(:func:`sweep_kind`) and never branch on it themselves.
"""
from dataclasses import dataclass

from .model_metrics import heat_map_metrics
from .model_paths import INTEGER_KEYS
from .model_point import model_point_key, run_model_point
from .plots import HEAT_MAP_METRICS
from .point import point_key, run_point
from .point_cost import crane_point_plans, model_point_plans


@dataclass(frozen=True)
class CraneSweep:
    """The built-in crane's sweep (a spec without ``model``)."""

    def point_job(self, spec):
        """(key function, point function, leading arguments): key(*args, point, settings),
        run(*args, point, settings)."""
        return point_key, run_point, ()

    def size(self, spec, point) -> float:
        """How large a point's model is (the cost estimate samples the largest): n_rfe."""
        return point.get("n_rfe", spec.run.n_rfe)

    def plans(self, spec, point, sampler):
        """(s to build the model, [RunPlan]) of one point (gpme_study.point_cost)."""
        return 0.0, crane_point_plans(point, spec.run, sampler)

    def heat_maps(self, spec) -> tuple:
        """The metrics drawn as heat maps."""
        return HEAT_MAP_METRICS

    def plot_options(self, spec) -> dict:
        """gpme_study.plots.write_plots' keywords beyond the table and axes."""
        return {}


@dataclass(frozen=True)
class ModelSweep:
    """A model file's sweep (a spec with ``model``: spec.model its ModelDocument)."""

    def point_job(self, spec):
        return model_point_key, run_model_point, (spec.model,)

    def size(self, spec, point) -> float:
        """The RFEM segments and other integer keys the point sets, summed."""
        return sum(v for name, v in point.items() if name.rsplit(".", 1)[-1] in INTEGER_KEYS)

    def plans(self, spec, point, sampler):
        return model_point_plans(spec.model, point, spec.run, sampler)

    def heat_maps(self, spec) -> tuple:
        return heat_map_metrics(spec.metric_table, spec.limits)

    def plot_options(self, spec) -> dict:
        units = {name: spec.model.unit(name) for name in spec.swept}
        units.update({name: v[0] for name, v in spec.metric_table.items()})
        return {"metrics": self.heat_maps(spec), "units": units, "parameters": spec.swept}


CRANE, MODEL = CraneSweep(), ModelSweep()


def sweep_kind(spec):
    """The kind of ``spec`` (a gpme_study.spec_points.SweepSpec): MODEL when it sweeps a
    model file, CRANE for the built-in crane."""
    return CRANE if spec.model is None else MODEL

"""Sweeps: plans of variants (``variants``), the runners (``single``: ``run_drop`` per variant;
``batch``: on the batched drop engine ``mtbmj.drop.engine_batch``; ``fast``: the fast engine), the
journaled driver that writes one table (``runner``), and SALib sensitivity (``sensitivity``).
"""
from mtbmj._package import lazy_exports

_LAZY = {
    "run_sweep": "mtbmj.sweep.runner",
    "read_table": "mtbmj.sweep.runner",
    "plan": "mtbmj.sweep.runner",
    "Journal": "mtbmj.sweep.runner",
    "SweepProgress": "mtbmj.sweep.runner",
    "SweepResult": "mtbmj.sweep.runner",
    "run_sensitivity": "mtbmj.sweep.sensitivity",
    "Range": "mtbmj.sweep.variants",
    "parse_vary": "mtbmj.sweep.variants",
    "grid": "mtbmj.sweep.variants",
    "sample": "mtbmj.sweep.variants",
    "from_csv": "mtbmj.sweep.variants",
    "variant_id": "mtbmj.sweep.variants",
    "BatchJob": "mtbmj.sweep.variants",
    "Variant": "mtbmj.sweep.variants",
    "flatten_summary": "mtbmj.sweep.variants",
    "OUTPUT_COLUMNS": "mtbmj.sweep.variants",
    "RUNNERS": "mtbmj.sweep.variants",
    "TABLE": "mtbmj.sweep.variants",
    "TABLE_CSV": "mtbmj.sweep.variants",
    "TRACES": "mtbmj.sweep.variants",
    "MANIFEST": "mtbmj.sweep.variants",
    "run_batch": "mtbmj.sweep.single",
    "run_variant": "mtbmj.sweep.single",
}
__all__ = ['BatchJob', 'Journal', 'MANIFEST', 'OUTPUT_COLUMNS', 'RUNNERS', 'Range', 'SweepProgress', 'SweepResult', 'TABLE', 'TABLE_CSV', 'TRACES', 'Variant', 'flatten_summary', 'from_csv', 'grid', 'parse_vary', 'plan', 'read_table', 'run_batch', 'run_sensitivity', 'run_sweep', 'run_variant', 'sample', 'variant_id']


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

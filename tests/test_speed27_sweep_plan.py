"""A sweep's plan computes the configuration's digest once (issue 27, item 2): its variant ids are
still each variant's own ``variant_id``."""
from __future__ import annotations

import mtbmj
from mtbmj import sweep
from mtbmj.sweep.runner import plan


def test_plan_ids_are_each_variants_own_id():
    cfg = mtbmj.load_config("S12")
    overrides = [{"fork.spring.preload_N": 150.0 + i, "sled.drop_height_mm": 60 + i} for i in range(5)] + [{}]
    for engine, duration in (("fast", None), ("mujoco", 0.5)):
        planned = plan(cfg, overrides, engine, duration)
        assert [v.id for v in planned] == [sweep.variant_id(cfg, o, engine, duration) for o in overrides]
        assert [v.index for v in planned] == list(range(len(overrides)))

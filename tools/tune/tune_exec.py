"""A persistent pool for the tuning runs: local processes or a Ray cluster.

The campaign executor (tools/benchmark/campaign.py) runs a fixed list of flights and
closes its pool; a search asks for a few flights at a time, hundreds of times,
so here the workers stay up for the whole search (a spawned worker pays about
a second to import JSBSim and numpy) and take any picklable task function: a
campaign RunSpec (tools/campaign.run_one: a logged flight and its Table 1
metrics) or a captured sweep or step flight (tune_sysid, tune_step).
Results come back in task order.
"""

from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

from silbridge.tools.benchmark.campaign import CampaignError


class TaskPool:
    def __init__(self, jobs: int | None = None, executor: str = "local",
                 ray_address: str | None = None):
        self.jobs = max(1, jobs or os.cpu_count() or 1)
        self.executor = executor
        self._pool = None
        self._ray = None
        self._ray_started = False
        if executor == "ray":
            from silbridge.tools.optional_deps import require
            require(["ray"], "ray", "--executor ray")
            import ray
            self._ray = ray
            if not ray.is_initialized():
                kw = {"address": ray_address} if ray_address else {
                    "num_cpus": self.jobs, "include_dashboard": False}
                ray.init(log_to_driver=False, **kw)
                self._ray_started = True
        elif executor != "local":
            raise CampaignError(f"unknown executor {executor!r}: use local or ray")

    def map(self, fn, tasks) -> list:
        tasks = list(tasks)
        if not tasks:
            return []
        if self._ray is not None:
            remote = self._ray.remote(num_cpus=1)(fn)
            return self._ray.get([remote.remote(t) for t in tasks])
        if self.jobs == 1:
            return [fn(t) for t in tasks]
        if self._pool is None:
            # spawn: every worker starts clean (no inherited JSBSim or shared-memory state)
            self._pool = ProcessPoolExecutor(max_workers=self.jobs, mp_context=get_context("spawn"))
        return list(self._pool.map(fn, tasks))

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        if self._ray_started:
            self._ray.shutdown()
            self._ray_started = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

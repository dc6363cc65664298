"""The run path every MuJoCo rig shares: the chunked rollout (with a refinement plan for the
stretches near a stop), MuJoCo's warnings read after every chunk, the divergence checks that end a
run in one line naming the rig, the time and the likely cause, the choice of callback (auto /
compiled / python) and the rerun on the Python twin when a compiled callback overflows.

A rig (the drop, the rolling front end, the whole bike) keeps its scene, its callback bodies, its
refinement plan, its reference and its signals; ``mtbmj.runpath`` steps it.

* ``guard``: MuJoCo's warning text routed away from the terminal and MUJOCO_LOG.TXT, the first
  raised warning read, and :func:`guard.check` (one ``RunError`` line per divergence).
* ``loop``: :func:`loop.stepped`, the chunked rollout under a :class:`loop.Plan` (the drop's "cut
  before a stop", the bike's "redo after the fact" over a :class:`loop.Refinement`, or
  :class:`loop.Coarse`), which keeps every sensor row with the state it describes, and
  :func:`loop.chunked`, the same returning whole state and sensor arrays.
* ``callbacks``: :func:`callbacks.choose` and :func:`callbacks.rerun_on_python`.
"""

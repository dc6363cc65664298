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
* ``steprule``: the step rule, one for a fork law whichever rig runs it: the step limits of a
  setup's laws and masses (:func:`steprule.limits`), the drop's steps (:func:`steprule.choose_timestep`,
  which ``compose.setup`` calls), the front end's (:func:`steprule.at_fine_step`), the whole
  fractions and even cuts the bike takes, and the stop zones every rig refines in.
* ``rig``: :class:`rig.Rig`, the one face every rig shows (presets, ``prepare``, ``run``,
  ``crosscheck`` with one signature, a short example case), and :class:`rig.Registry`
  (``mtbmj.rigs.RIGS`` lists the rigs).
* ``crosscheck``: :class:`crosscheck.CrosscheckResult`, the one result of every rig's cross-check
  against its ODE reference (per signal the largest difference over the series, its unit, the
  peaks in both runs, the tolerance and the verdict; both wall times; one line, one dict).
"""

"""`mctools sweep`: initial-position studies of thesis ch. 5 / 7.2 run with mcsim.

* `angles`   one run per initial angle (mechanics.theta0_deg): per-angle table and distribution
             of the startup metrics (step1_err_deg, step12_err_deg, polarity_correct,
             init_pos_err_deg, init_pos_time_s, ...); optional pass/fail flags (exit 1).
* `table7_1` thesis Table 7.1: mean |Step I error| of the linear (5.5) and nonlinear (7.1) cost
             for m = 3, 4, 5 and the Step I phase-current peak in per unit of the rated peak.
* `noise`    thesis Fig. 7.4: Step II polarity decisions (generalized vs DVI) over many seeded
             trials with random initial angles, per current-noise level.
* `seeds`    one scenario over scenario.seed = 1..N: median, p5/p10/p90/p95, min/max of every
             numeric metric; on the local cores or on a Dask distributed cluster (--scheduler).
* `envelope` the robustness envelope of sensorless control: estimator parameter errors (one at a
             time) x scenarios, each cell over seeds 1..N, classified holds / trips / runs off.

Every number comes from the metrics.json (and, for the Step I current peak, the trace.csv) of
`mcsim run` processes, `--jobs` at a time. Results are printed as markdown and can be written as
JSON (`--json`) and markdown (`--md`).

One module per sweep, each with `add_parser(ssub)` registering its subcommand; `common` holds
what they share (argument checks, the mcsim runs, the numbers, the outputs).
"""

from __future__ import annotations

from mctools.sweep import angles, envelope, noise, seeds, table7_1, zoo

SWEEPS = (angles, table7_1, noise, seeds, envelope, zoo)  # in the order `mctools sweep --help` lists them


def add_parser(sub) -> None:
    p = sub.add_parser("sweep", help="initial-position sweeps with mcsim (thesis ch. 5, 7.2)")
    ssub = p.add_subparsers(dest="sweep_command", required=True, metavar="SWEEP")
    for sweep in SWEEPS:
        sweep.add_parser(ssub)

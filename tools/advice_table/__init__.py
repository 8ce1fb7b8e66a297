"""Build the advisor's table (``curv/data/advisor_table.json``) from a study run.

The table behind :func:`curv.advise`: a study over a grid of densities, noise levels and
irregularities (the study's own tasks, meshes, runner and metrics), noisy closed analytic
surfaces of random shape beside it, then, on every mesh, the advisor's own feature measures. It
stores

- ``calibration``: the noise measure's floor, density term and gain
  (``raw² = a² + c density⁴ + (b noise)²``, least squares over all the table's meshes of known
  noise) and the angle jitter per noise level of the irregularity measure
  (``raw² = clean² + (c level)²``, least squares over each mesh and its noise-free twin);
- ``points``: per mesh, the measured ``(density, noise level, irregularity)``;
- ``median_erel``: per mesh and variant, the median e_rel against the exact curvature (3
  significant digits);
- ``kernel``: the noise axis transform (linear or square root), the axis scales (standard
  deviation of each coordinate over the points) and the bandwidth, the pair with the lowest
  leave-one-out mean regret (each mesh advised from all the others);
- ``truth``: per mesh, its key, true noise, planar irregularity and density from the exact
  curvature (for checks; the advisor does not read it);
- ``metadata``: the exact command, the settings, the date, timings.

Regenerate the shipped table (1260 study meshes: hexagon densities 817, 1801, 3169, 7057 and
12481 x noise levels 0, 0.05, 0.1, 0.2, 0.33, 0.6, 1 x irregularities 0, 8, 16, 25 x the three
Monge patches x 3 samples; plus sphere, ellipsoid and torus at 642, 2562 and 10242 vertices x the
same noise levels x 3 random shapes: 1449 meshes; 28.5 CPU-minutes, 32 minutes wall with 2 workers
on 2 cores shared with another study run, from scratch)::

    python -m tools.advice_table --work advisor-study-3 --workers 2

Every grid setting is a default (``--samples``, ``--densities``, ``--noise``,
``--irregularity``, ``--closed``, ``--closed-vertices`` change them).

The shipped table is that base table extended (``extend``) with the option candidates (jet degree
3 and 4 at R2-R4; ``normals="fit"`` at ``fit_range`` 2 and 4 for nc, qs, an, mru, ru, icc) as new
columns, run on every sample-0 mesh of the base table (patches and closed surfaces), and with
coarse meshes as new rows (every candidate): patches
of 217, 331 and 469 vertices, evaluated away from the border at the largest of R4..R1 that leaves
at least 30 vertices, and sphere, ellipsoid and torus at 162, 252 and 362 vertices, one sample
each::

    python -m tools.advice_table extend --base base.json --work advisor-ext --workers 2

Then the option candidates are run on the closed surfaces of the other two samples too (the closed
surfaces are few beside the patches; their option columns were empty there), two more random
surfaces of every coarse setting are added as rows (every candidate: the best call changes fastest
with the surface on coarse meshes), and every mesh is measured again for the shape, tessellation
and raw noise columns (:data:`EXTRA_COLUMNS`: border share, edge length spread, valence spread,
anisotropy, curvature spread, saddle share, uncalibrated noise measure; the meshes are rebuilt from
their keys, only the measuring fit runs), which a forward selection by grouped leave-one-out regret
turns into further kernel axes (:func:`select_axes`)::

    python -m tools.advice_table fill --table extended.json --out filled.json --work advisor-fill --workers 2
    python -m tools.advice_table fill --table filled.json --out coarse.json --kinds --coarse-samples 3 --work advisor-coarse --workers 2
    python -m tools.advice_table refeature --table coarse.json --work advisor-refeature --workers 1

(``base.json``: the base table the first command writes, ``--out base.json``; ``extended.json``
the second's ``--out``). The fill ran 150 meshes (5036 estimates) in 151 s wall with 2 workers,
the coarse fill 630 meshes (42,840 estimates) in about 2 minutes wall with 2 workers, the refeature
measures every mesh (1764 of them took 192 s wall, 102 CPU-s, with 1 worker) and chose the axes in
about 7 minutes more on the loaded machine (two leave-one-outs per trial; a rerun over the same
``--work`` only chooses).

Then the option candidates are run on the patches of samples 1 and 2 at 817, 1801 and 3169
vertices (their option columns were empty: an option call was weighed on other meshes than a named
call), closed surfaces of about 480 vertices (between the coarse 362 and the grid's 642; three
random shapes, every candidate) are added as rows, and the extra columns and axes are measured and
chosen again (the rows of the meshes measured before come from the same ``--work``)::

    python -m tools.advice_table fill --table shipped.json --out options.json --kinds quadratic ellipsoid_patch trigonometric --sizes 817 1801 3169 --work advisor-options --workers 1
    python -m tools.advice_table fill --table options.json --out closed.json --kinds --coarse-samples 3 --coarse-closed-vertices 162 252 362 482 --work advisor-closed --workers 1
    python -m tools.advice_table refeature --table closed.json --work advisor-refeature --workers 1

(504 meshes, 20,160 estimates, 356 CPU-s; 63 meshes, 105 CPU-s; with 1 worker each.) Then the
option candidates are run on the 7057-vertex patches of samples 1 and 2, a noise level between the
grid's 0 and 0.05 of the paper's is added where the noise measure resolves it: the noise twins at
0.015 of every noise-free mesh of 2562-10242 vertices (the same surface, tessellation and noise
directions, :func:`noise_jobs`), every candidate, as rows; and the measures and axes again::

    python -m tools.advice_table fill --out options7057.json --kinds quadratic ellipsoid_patch trigonometric --sizes 7057 --work advisor-twins --workers 1
    python -m tools.advice_table fill --table options7057.json --out twins.json --kinds --noise-levels 0.015 --sizes 2562 3169 7057 10242 --work advisor-twins --workers 1
    python -m tools.advice_table refeature --table twins.json --work advisor-refeature --workers 1

(168 meshes, 6720 estimates, 331 CPU-s; 90 meshes, 6120 estimates.) Then closed surfaces between
the grid's sizes are added as rows, where the winners of the noise-free ellipsoids change (nc R1 up
to 642 vertices, jet R2 degree 4 from 2562): 1000, 1600 and 5000 vertices, three random shapes at
every noise level, every candidate; and the measures and axes again::

    python -m tools.advice_table fill --table twins.json --out closed2.json --kinds --coarse-samples 3 --coarse-closed-vertices 162 252 362 482 1000 1600 5000 --work advisor-closed2 --workers 1
    python -m tools.advice_table refeature --table closed2.json --work advisor-refeature --workers 1

(189 meshes, 12,852 estimates, 502 s wall with 1 worker at niceness 10 on the loaded machine.) Then every
mesh is measured again for the residual measures (``noise_raw4``, ``residual_ratio``:
:mod:`curv.advice.residuals`, which tell a quadric's model error from noise) and the axes chosen
again, over the packaged table (no estimator runs)::

    python -m tools.advice_table refeature --table closed2.json --work advisor-refeature2 --workers 1

(2736 meshes measured in 1114 s wall with 1 worker at niceness 10 on the loaded machine.) The coarse rows are
measured with the base table's calibration; the kernel is refitted by leave-one-out over all rows. 217 vertices is left out: on
its hexagon no vertex is farther than R4 from the border, so the study evaluates none. The study
directory resumes and keeps the measured rows (``advisor_rows.json``), so a long run may be split
and a rerun over a finished directory only refits the calibration and the kernel (seconds).

Last, the anisotropy axis became logarithmic (:data:`EXTRA_TRANSFORMS`) and the axes were chosen
again over the packaged table's stored points (nothing measured or run; 579 s wall at niceness 10)::

    python -m tools.advice_table reselect
"""

from .base import DEFAULT_OUT, build_table, make_table, table_settings
from .extend import evaluated_for_table, option_variants, table_mesh, variant_errors

__all__ = ["DEFAULT_OUT", "build_table", "make_table", "table_settings", "evaluated_for_table", "option_variants",
           "table_mesh", "variant_errors"]

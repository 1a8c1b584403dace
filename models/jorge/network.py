r"""The label network of seed 004 (section 4), built with :mod:`dbn` and solved with
:mod:`inference.exact`.

Nodes: a hidden label node ``x{k}`` per stroke ``k`` (its states are the admissible labels
:math:`L_k`, :mod:`models.jorge.labels`), a binary restriction node ``r{i}_{j}`` for every
pair of children sharing a parent (observed :math:`r = 1`, eq. 5, hard evidence; with
``LabelParams.split_cover``, an option off by default, the shared parent is its parent too
and a split that loses people weighs less, :data:`FITTED_SPLIT_COVER`), and the
stroke's dominant colours as soft (virtual) evidence on ``x{k}`` (eq. 6; proper likelihood
ratio by default, the equation as written as an option), times, where the stroke has a
recorded region size, the size evidence on the number of people of the label
(:func:`models.jorge.labels.size_log_likelihood`; our addition, ``size_evidence``).

Links (seed 004, sec. 4): ``i -> j`` when stroke ``j`` starts after ``i`` ends and the gap
is physically possible. A region's centre jumps when regions merge or split, so we admit
``distance <= radius + v_max * gap`` (``radius`` is our addition; the seed gives only the
speed bound) and ``gap <= max_gap_frames``. A node has at most 2 parents and 2 children;
candidates are taken by increasing spatial gap (the seed's pruning preference), greedily
in start order, as an on-line builder must.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from dbn.bayesnet import BayesNet
from dbn.cpds import TabularCPD
from dbn.errors import InputError, ModelError, ShapeError, TimeOrderError, UnknownVariableError
from dbn.variables import DiscreteVariable
from inference.exact import JunctionTree, map_assignment
from models.jorge.labels import (
    Label,
    LabelObjects,
    LabelParams,
    admissible_labels,
    birth_stroke,
    child_table,
    cohort_size,
    colour_log_likelihood,
    format_label,
    gain_bins_rise,
    label_objects,
    palette_count_log_likelihood,
    palette_gain_log_likelihood,
    restriction_table,
    root_table,
    size_log_likelihood,
    structure_of,
    union_rows,
)
from models.jorge.memo import ChainMemo, EvidenceMemo, TableMemo
from models.jorge.strokes import Stroke, _check_colours

__all__ = [
    "NetworkConfig",
    "FITTED_LABELS",
    "FITTED_PALETTE_COUNTS",
    "FITTED_PALETTE_GAINS",
    "FITTED_SPLIT_COVER",
    "LabelGraph",
    "WindowNet",
    "Inference",
    "node_name",
    "restriction_name",
    "kept_name",
    "colour_name",
    "solve",
]


def node_name(k: int) -> str:
    """Name of the hidden label node of stroke ``k``."""
    return f"x{k}"


def restriction_name(i: int, j: int) -> str:
    """Name of the restriction node of the sibling pair ``i < j``."""
    return f"r{min(i, j)}_{max(i, j)}"


def kept_name(k: int) -> str:
    """Name of the observed node carrying the mass node ``k``'s pruned domain kept
    (``NetworkConfig.truncate_pruned``), times the row sums of the chain factor
    (``NetworkConfig.chain_palette``, :meth:`LabelGraph.chain_log_ratio`)."""
    return f"m{k}"


def colour_name(k: int) -> str:
    """Name of the explicit colour node (only in :meth:`WindowNet.with_colour_nodes`)."""
    return f"y{k}"


FITTED_LABELS = LabelParams(
    p_new=0.06284805091487669,
    p_merge=0.9171519490851233,
    p_merge_one_split=0.7058823529411765,
    p_merge_both_split=0.2,
    p_split=0.9688279301745636,
    p_part=0.3383199079401611,
    max_group_size=5,
    new_group_probs=(0.6735966735966736, 0.17775467775467776, 0.07172557172557173, 0.035343035343035345,
                     0.04158004158004158),
    p_join=0.10806223479490806,
    child_new_groups=False,
)
"""The label parameters of the default network: the output of
:func:`models.jorge.fit.search_settings` on the declared training split
(``models.jorge.fit.TRAIN_SEQUENCES``, fitted with simulation seeds 100-109, scored with
seed 100), with the box link gate (``gate="boxes"``, ``v_box`` 0.5; issue 16). Training
errors (mean over the six training sequences), ML parameters with palette evidence, no new
groups: box gate 0.2762 (chosen; ``v_box`` 0.25: 0.2814), scaled gate 0.2846, pixel gate
0.2949; with new groups and joins 0.3115 (boxes) / 0.3137 (scaled). Re-scored with seeds
100-104: box gate 0.2929, scaled 0.3046. Before issue 16's
palette evidence (issue-16 first round): pixel gate 0.322 / scaled 0.292, and new groups
0.37-0.43. So: the box gate, the maximum-likelihood CPD parameters, no new groups or joins
(the evidence tells a new group from a new person now, but in the training crowds a
stroke's newcomers are rarely a whole new group and the error rises).
Second round (issue 16, with the gain table, ``size_once`` and the instant-cap fix; seed 100):
box gate, ML, no new groups, size once 0.2751, without 0.2755 (kept: the 0.0004 is far below the
seed-to-seed noise, about 0.005, and counting the size once loses the size evidence that lets a
group of 4-5 seen first as a group be recovered, tests/models/jorge/test_jorge_groups.py); the gain
table instead 0.2823-0.2852; new groups at best 0.2951 (gain table, size once), 0.3092 with the
marginal count table. New groups still lose on training.
Fourth round (issue 16; cohort-coded new groups, pruned rows truncated instead of renormalised,
new groups at roots only as a grid option, ``python -m models.jorge.fit --gates boxes``): the
search is scored on seeds 100-104 (:data:`models.jorge.fit.SCORE_SEEDS`) and keeps the lowest
mean: the gain table without the count table, no new groups, size once, 0.2771 (without size
once 0.2775; both tables 0.2806-0.2808; the count table 0.2863-0.2869; new groups at roots
0.2870 (gain, size once) / 0.2879 (count), at any stroke 0.2868 (gain, size once; 0.3165
without size once) / 0.3018 (count); the previous parameters 0.3021 or more). The CPD
parameters are unchanged.
Fifth round (issue 16; a member of a new group takes the palette of the first stroke frozen
to it alone, :meth:`LabelGraph.freeze`, so the members of a pair that entered together are
no longer exchangeable at every later split; the gain table counts such a member as known
and was refitted): the same search keeps the same point, 0.2772 (without size once 0.2788);
new groups at roots 0.2783 (was 0.2870), at any stroke 0.2813 (was 0.2868), both with the
gain table and size once; both tables at roots 0.2845; the count table 0.2856-0.2869; the
previous parameters 0.3021 or more. New groups are now within the seed-to-seed spread of
no new groups on training, but not below it, so they stay off.
Sixth round (issue 16; the merge test of the link rule, ``NetworkConfig.merge_area``, as a
grid dimension, the parameters refitted under each link rule; the search now keeps only
points that label every training set at least 20x faster than real time,
:data:`models.jorge.fit.REALTIME_BAR`): the merge test, the gain table, no new groups, size
once, 0.2721 (per seed 0.2784, 0.2819, 0.2671, 0.2660, 0.2670; slowest training set 47.7x
real time); without the merge test the same point scores 0.2772 (41.8x). Faster points
come next: new groups at roots 0.2730 (22.3x), both tables 0.2731 (40.6x). The most
accurate point, both tables with new groups anywhere and joins, 0.2703, labels the PETS2009
S1 crowds at 2.4x real time (5x in the benchmark), so the bar excludes it; the gain table
with new groups anywhere 0.2724 (5.5x). The CPD parameters above and
:data:`FITTED_PALETTE_GAINS` are refitted with the merge test.
Seventh round (issue 16; the evidence and the merge CPD vectorised, the same labels on
every training set): the search re-run gives the same errors and the same choice; the
slowest training sets now: the kept point 32.6x (two labellers sharing 2 cores; about 54x
alone), new groups at roots 36.0x, both tables 28.9x, both tables with new groups and
joins 5.8x (still under the bar), the gain table with them 8.6x.
Eighth round (issue 16): the grid gains ``"joins"`` (no new groups, but a stroke may add one
new object to what it inherits, ``p_join`` fitted, 0.115: a person who enters the view inside
another's region, the first mistake of most crowd strokes when the links are the true ones);
the search also scores SIMULATED meetings of 3-5 people (scenes 100-104,
:data:`models.jorge.fit.MEETING_SIZES`), since the real training split has no CAVIAR-like
group of three or more; and the default stays unless a point beats it by more than one
standard error of the paired per-seed differences (:data:`models.jorge.fit.DEFAULT_POINT`).
On the real training sequences alone (one labeller at a time) joins win: both tables with
joins and size once 0.2584 (per seed 0.2682, 0.2639, 0.2495, 0.2672, 0.2433; slowest set
22.9x), the gain table with joins 0.2667 (29.7x), this default 0.2721 (0.0137 better, one
standard error 0.0043). On the meetings they lose: k = 3 / 4 / 5 errors 0.037 / 0.114 / 0.134
for both tables with joins, 0.005 / 0.049 / 0.151 for this default (a member who arrives
next to the group, or comes back after a brief break, is taken for a newcomer joining it).
Scored on both (each set weighs the same): both tables with joins 0.20397, the gain table
without size once 0.20401, this default 0.20415, the gain table with joins 0.2099; the lowest
beats the default by 0.0002 with one standard error 0.0087, so the default and its
parameters stay.
Ninth round (issue 16): the re-identification pass (:func:`models.jorge.online.reidentify`)
also asks of an object born inside a group (a newcomer who joined, or a member of a new
group) whether it is a lost object, once it has a stroke alone; labels with new groups off
and no joins (this default) are unchanged. The search again (boxes gate, seeds 100-104,
one labeller at a time) keeps the default: both tables with joins and size once 0.2026
(0.2040 before; slowest set 41.5x), the gain table without size once 0.2040, this default
0.2041 (71.2x), the gain table at roots only 0.2047, the gain table with joins 0.2080
(0.2099 before); the lowest beats the default by 0.0015 with one standard error 0.0093.
Two other changes scored worse on the same sets and were not kept: entry probabilities
that depend on whether a stroke starts at the edge of the view (``p_join`` 0.188 at the
edge, 0.032 inside; with joins at the edge only, 0.2046, scored before the change to
re-identification), and a superseded ancestor kept as a second parent when a region grows
back (0.2116 and 0.2321).
Tenth round (issue 16): a bug in the SIMULATED meetings the search scores
(:func:`models.jorge.meeting.simulate_meeting`): of a pair meant to arrive together, side by
side (``pair_prob`` 0.3), only the second took the shared direction, so no scene had a pair
that entered the view together. I looked because new groups or joins are what such pairs
need, and the held-out wk2gt was known from earlier rounds' benchmark runs to be lost on
them (its strokes of two people are wrong with correct links): so this round's validation
figure is not blind to why I looked, though nothing was chosen on it. The fixed scenes hold
such pairs; the same search (boxes gate, seeds 100-104, two labellers sharing 2 cores) then
replaced the default: both palette tables with joins and size once 0.2135 (per seed
0.2172, 0.2267, 0.2171, 0.2058, 0.2006; slowest set 42.2x) against the previous default's
0.2566 (0.2810, 0.2327, 0.2862, 0.2299, 0.2533; 71.3x), every seed lower; next both tables
with joins without size once 0.2170, both tables with new groups anywhere 0.2280 (7.2x,
under the bar). The grid then gained its missing cell, new groups at roots only with joins
anywhere (``"roots_joins"``), and the search over the joins rows and these (incumbent:
both tables with joins) replaced it once more: both tables, new groups at roots, joins,
size once 0.2119 (0.2135, 0.2280, 0.2175, 0.2048, 0.1957; slowest set 22.8x with two
labellers sharing 2 cores, 40.9x alone in the full benchmark), 0.0016 lower, one standard
error of the paired differences 0.0012: a narrow win, but the declared rule's. The points
faster with one labeller at a time are not lower, so the choice does not hang on the shared
cores. So the default is now: new groups of ``m`` people at roots only (``q_m`` and
``p_join`` 0.115 as fitted, ``child_new_groups`` False), both :data:`FITTED_PALETTE_COUNTS`
and :data:`FITTED_PALETTE_GAINS`, size once (:data:`models.jorge.fit.DEFAULT_POINT`); the
CPD parameters are the same fit. Last, a joiner's palette: a newcomer who joins an inherited
label was counted as born alone, credited with its birth region's colours, so the stroke of
that person leaving the group later looked less like them than like a new object (first
mistakes on the search's own meeting scenes). It is now known only with its whole birth
label, like a new group's member, until it is seen alone (:meth:`LabelGraph.freeze`), in
the network and in the fit; :data:`FITTED_PALETTE_GAINS` refitted. The search over the
joins rows again: both tables with new groups at roots and joins, size once 0.20836 (per
seed 0.2140, 0.2249, 0.2162, 0.1848, 0.2019; slowest set 27.5x with two labellers), joins
alone 0.20840, so the default stays (0.2119 before the fix: lower, but within one standard
error of the paired differences, 0.0044; the rows without joins, which the fix touches only
through the refitted gain table, were 0.04 behind and not re-run).
Eleventh round (issue 16): three faults found on the search's own meeting scenes (seeds
100-104); the CPD parameters and tables are unchanged. (1) The re-identification pass
(:func:`models.jorge.online.reidentify`) examined the objects in id order, which puts a
new group's members after every lone newcomer: a later newcomer took the earlier object
first and the member it should continue was left with no candidate (scoring sets 0.2084 ->
0.2052). (2) Inside the window a member of a new group or a joiner leaving alone was scored,
stroke after stroke, on the group's birth palette, while "a newcomer born as it left" was
scored on its own first stroke, so the member vanished and a newcomer walked on; the
``NetworkConfig.chain_palette`` node scores a person who continues alone on the parent
stroke's palette (0.2052 -> 0.2024, no seed worse). (3) A group that stood together for
many strokes was pulled to one person more or fewer than it held by the palette count and
gain evidence, summed in full at every stroke of the same region (as the size was before
``size_once``). The search gained a dimension, that evidence's weight where a region
continues (``NetworkConfig.palette_continued``: 1, 0.75, 0.5), and the full grid (boxes
gate, 240 points, seeds 100-104, two labellers on 2 cores) replaced the default by both
tables, new groups at roots and joins, the size counted at every stroke (``size_once``
False) and the palette counts weighed 0.5 where a region continues: 0.1974 (per seed
0.2162, 0.1979, 0.2060, 0.1764, 0.1905; slowest set 25.6x) against 0.2024 (0.2175, 0.2109,
0.2114, 0.1731, 0.1991; 23.4x), 1.8 standard errors of the paired differences; next the
same with 0.75, 0.1975, and with size once and 0.75, 0.1994. Lower but too slow: new groups
anywhere with 0.5, 0.1988 (9.2x).
Twelfth round (issue 16): a member of a group seen alone for a moment while the others were
hidden, then the whole group again (found on training-side SIMULATED meetings, scenes 105-
114, k = 4: three of ten scenes had their first mistake there). The link rule dropped the
group's stroke as a parent, superseded by the member's, and the restriction of eq. 5
forbade the member inside the group's next stroke anyway, so the group came back as the
member or the member plus a newcomer, even with the true links (true-link error on those
scenes 0.164 -> 0.094 for k = 4, 0.181 -> 0.103 for k = 5 with the restriction fixed,
:func:`models.jorge.labels.restriction_allows`). ``NetworkConfig.nested_links`` keeps the
group's stroke as a second parent when the member's box is a part of it; its threshold 2
was chosen among 1.5, 2 and 3 on the search's scoring sets at the eleventh round's point
(1.5: 0.1957, 2: 0.1954, 3: 0.1970, off: 0.1974; each refitted: 0.1999, 0.1984, 0.1997). The fit counts a
nested link's piece as a proper part (:func:`models.jorge.fit.count_events`); refitted on
the same split: ``p_merge_one_split`` 0.42 -> 0.50, ``p_merge_both_split`` 0.25 -> 0.18,
``p_part`` 0.36 -> 0.34, ``p_join`` 0.115 -> 0.108, the gain table; the count table and
the size fit unchanged. The full grid again with nested links (boxes gate, 240 points,
seeds 100-104, two labellers on 2 cores) chose both tables, new groups at roots and joins,
the size once and the palette counts weighed 0.75 where a region continues: 0.1926 (per
seed 0.2214, 0.1950, 0.1911, 0.1632, 0.1925; slowest set 23.2x) against the eleventh
round's default 0.1974 (0.2162, 0.1979, 0.2060, 0.1764, 0.1905), 1.2 standard errors of
the paired differences; next the same with the size at every stroke, 0.1928, and with
weight 1, 0.1932; the eleventh round's point with nested links 0.1984. On the training-side
scenes 105-124 (not used to choose): 0.127 -> 0.108 mean scene error over k = 3-5 (24
scenes better, 8 worse), strokes of 3+ people 0.37 / 0.47 / 0.49 -> 0.36 / 0.38 / 0.38.
Fifteenth round (issue 16): refitted on the same split under the merge cover test of the
link rule (``NetworkConfig.merge_cover`` 0.2), which drops spurious second parents, so
fewer two-parent strokes are counted and more of them are true merges: ``p_merge_one_split``
0.50 -> 0.71, ``p_merge_both_split`` 0.18 -> 0.20, ``p_split`` 0.956 -> 0.969, ``p_new``
0.0616 -> 0.0628; ``p_merge``, ``p_part``, ``p_join``, :math:`q_m` moved by less than 0.003;
the gain table refitted; the count table and the size fit unchanged (they do not depend on
the links). The full grid re-run under it (boxes gate, 240 points, seeds 100-104) keeps the
default point: 0.1930 (per seed 0.1923, 0.2099, 0.2198, 0.1685, 0.1743; slowest set 23.7x).
Its lowest point, the same without the area test (``merge_area`` 0, the cover test alone),
0.1856, is within one standard error of it (paired -0.0074, standard error 0.0082).
``tests/models/jorge/test_jorge_fit.py`` re-runs the fit (not the search, about 25 minutes
on 2 cores) and checks the fitted numbers."""


FITTED_SPLIT_COVER = (1.0, 1.0, 0.68, 0.9871794871794872, 0.94)
"""An option, off by default: :math:`p_n` for ``LabelParams.split_cover`` (issue 16's
sixteenth round), the probability that the two children of a group of ``n`` people that
take disjoint parts of it hold all of its people, fitted by
:func:`models.jorge.fit.fit_split_cover` on the declared training split (the rule's links,
seeds 100-109; groups of 3: 16 of 23 splits, of 4: 76 of 76, of 5: 46 of 48, add-one
smoothed). Seed 004's pieces are drawn independently and eq. 5 only forbids overlap, so
its prior gives a partition 6 / 12, 14 / 50 and 30 / 180 of the disjoint pairs of a group
of 3 / 4 / 5 (:func:`models.jorge.labels.split_loss_weights`). Turn it on with
``NetworkConfig(labels=replace(FITTED_LABELS, split_cover=FITTED_SPLIT_COVER))``; the
window inference uses it, and since issue 16's seventeenth round the instant (eq. 12)
labels too (:meth:`models.jorge.online.OnlineLabeller.instant_posterior`, given the
group's current label).

Not the default: on the search's scoring sets (the training sequences and SIMULATED
meetings) with seeds 100-104 and fresh seeds 245-264 and 265-304, 65 sets, the combined
error fell from 0.1958 to 0.1930, paired -0.0028 with standard error 0.0014 (-1.97 SE; lower
on 35 of 65 sets); meetings 0.093 -> 0.087, their strokes of 3+ people for k = 3 / 4 / 5
0.149 / 0.299 / 0.393 -> 0.152 / 0.253 / 0.383, the real training sequences 0.2472 -> 0.2463.
The rule declared before that second, larger comparison asked for -2 SE, so it did not land
(:data:`models.jorge.fit.CONFIRM_SEEDS` records every comparison). A third look, with the
instant labels using it too, on 40 fresh seeds (305-344) alone: 0.1973 -> 0.1948, paired
-0.0026 (standard error 0.0020), lower on 18 of 40; meetings of k = 3 / 4 / 5 0.065 / 0.093 /
0.140 -> 0.069 / 0.076 / 0.126, the PETS2009 S1 crowds 0.601 / 0.795 -> 0.603 / 0.797; not
landed (the rule asked for -2 SE). It helps groups of four and five and costs groups of three
and the crowds a little: try it where groups of four or more are common."""


FITTED_PALETTE_COUNTS = (
    (-7.990238185720363, -7.990238185720363, -7.990238185720363, -7.990238185720363, -7.990238185720363, -0.004073325387635786, -7.990238185720363, -7.990238185720363, -7.990238185720363, -7.990238185720363, -7.990238185720363, -7.990238185720363, -7.990238185720363),
    (-6.934397209928558, -6.934397209928558, -6.934397209928558, -6.934397209928558, -6.934397209928558, -5.324959297494458, -3.2208251432242503, -1.2749149941689373, -0.7795391159121404, -1.6769018379007767, -3.7563433795806125, -6.934397209928558, -6.934397209928558),
    (-5.8916442118257715, -5.8916442118257715, -5.8916442118257715, -5.8916442118257715, -5.8916442118257715, -5.8916442118257715, -5.8916442118257715, -5.198497031265826, -2.0204432009178803, -1.0794598564533535, -1.031831807464099, -1.9998239137151446, -4.505349850705881),
    (-5.5134287461649825, -5.5134287461649825, -5.5134287461649825, -5.5134287461649825, -5.5134287461649825, -5.5134287461649825, -5.5134287461649825, -5.5134287461649825, -5.5134287461649825, -1.9580806846755685, -1.0707774896746658, -1.0360919316867756, -2.0794415416798357),
    (-5.3981627015177525, -5.3981627015177525, -5.3981627015177525, -5.3981627015177525, -5.3981627015177525, -5.3981627015177525, -5.3981627015177525, -5.3981627015177525, -5.3981627015177525, -4.011868340397862, -1.7092832474038164, -0.8763741244687124, -1.0674293612314218),
)
"""Default ``NetworkConfig.palette_count_table``: :math:`\\log p(c \\mid k)` of the number
:math:`c = 0..12` of distinct colours in a stroke's palette given its :math:`k = 1..5`
people (row ``k - 1``; 5 stands for 5 or more), add-one smoothed frequencies from
:func:`models.jorge.fit.fit_parameters` on the declared training split (seeds 100-109).
Beside :data:`FITTED_PALETTE_GAINS` it is part of the default
again since issue 16's tenth round (see :data:`FITTED_LABELS`).
With it the documented search (:data:`models.jorge.fit.SEARCH_GRID`, scored with seed
100) gives training errors: scaled gate, ML parameters 0.2846 without new groups (chosen;
0.2917 with the previous parameters, which carry no palette evidence) and 0.3137 with
them; pixel gate 0.2949 / 0.3166. Re-scored with seeds 100-104 (scaled gate): ML 0.3046
without new groups, 0.3404 with them, previous parameters 0.3202. New groups still lose
on training (issue 16: in the crowds a new group is rarely the whole story, see
``benchmarks/jorge.py``), so they stay off; see :data:`FITTED_LABELS`.
Third round (issue 16, simulated meetings): the row of 5 people no longer counts the strokes
of 6-30 people (off the model, :func:`models.jorge.fit._palette_count_table`); it read
:math:`p(12 \\mid 5)` = 0.68, the crowds' count (0.34 for strokes of exactly 5). Search re-run (seed 100): the same choice (box gate, ML, no new groups), training
error 0.2712 (0.2751 before); on SIMULATED meetings (10 scenes per k, seeds [0, i]) the
3+ error for k = 4 fell from 0.51 to 0.44, k = 3 and 5 unchanged. The box-gate half of
the grid re-scored on seeds 100-104: ML 0.2872 (size once 0.2864), ML with the gain table
instead 0.2763 (:data:`FITTED_PALETTE_GAINS`), both 0.2831, previous 0.3054, any with new
groups 0.29-0.41. Fourth round: the search scores with seeds 100-104 and the gain table
replaced this one as the default (:data:`FITTED_LABELS`); set
``NetworkConfig(palette_count_table=FITTED_PALETTE_COUNTS, palette_gain_table=(),
size_once=False)`` for the third round's evidence."""


FITTED_PALETTE_GAINS = (
    (
        (-3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006),
        (-7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -0.011527505171067383, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482, -7.646831391430482),
        (-5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -0.15219181534192538, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262, -5.135798437050262),
        (-5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.170483995038151, -4.254193263163997, -5.863631175598097, -4.477336814478207, -0.0953101798043249, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097, -5.863631175598097),
        (-5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318, -2.8526314299133175, -5.337538079701318, -5.337538079701318, -3.951243718581427, -4.6443908991413725, -3.1403135023650988, -3.951243718581427, -0.2749430466743512, -5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318, -5.337538079701318),
    ),
    (
        (-6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -0.02768342874841674, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177, -6.778784897685177),
        (-5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -4.844187086458591, -3.139438994220166, -1.1935288451648527, -0.9321640810304451, -1.8237622003142289, -4.151039905898646, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537, -5.537334267018537),
        (-4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -2.6567569067146595, -1.845826690498331, -1.4039939382192916, -1.9636097261547143, -3.349904087274605, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455, -4.04305126783455),
        (-4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -3.6463198396951406, -2.03688192726104, -1.0813704822336037, -1.486835590341768, -2.26002547857525, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325, -4.74493212836325),
        (-5.198497031265826, -5.198497031265826, -5.198497031265826, -5.198497031265826, -5.198497031265826, -4.505349850705881, -4.505349850705881, -4.099884742597716, -3.5890591188317256, -4.505349850705881, -5.198497031265826, -4.099884742597716, -0.5735242179815546, -1.5349353851361793, -3.2525868822105126, -5.198497031265826, -5.198497031265826, -5.198497031265826, -5.198497031265826, -5.198497031265826, -5.198497031265826, -5.198497031265826, -5.198497031265826, -5.198497031265826, -5.198497031265826),
    ),
    (
        (-5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -5.83773044716594, -4.73911815849783, -2.841998173611949, -1.5610643281498846, -0.8889705567877716, -1.4557038124920583, -3.758288905486104, -5.83773044716594, -5.83773044716594),
        (-4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -2.639057329615259, -1.4604023332736125, -1.3173014896329391, -3.332204510175204, -3.332204510175204, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515, -4.02535169073515),
        (-3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -2.169053700369523, -1.7635885922613588, -2.456735772821304, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135, -3.5553480614894135),
        (-4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -2.8183982582710754, -1.4966424182887559, -1.37147927533475, -2.0074680420547466, -3.5115454388310208, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966, -4.204692619390966),
        (-4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -3.8066624897703196, -0.7862376036259573, -1.3643154544011153, -3.4011973816621555, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265, -4.499809670330265),
    ),
    (
        (-5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -5.209486152841421, -2.2650471736749807, -1.1664348850068706, -1.1664348850068706, -1.8772816426662169, -4.516338972281476),
        (-4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -2.908720896564361, -1.2992829841302609, -1.5224265354444706, -2.6210388241125804, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471),
        (-3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -1.8562979903656263, -2.367123614131617, -3.4657359027997265, -2.772588722239781, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265, -3.4657359027997265),
        (-3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.1780538303479458, -3.871201010907891, -1.9252908618525775, -1.3862943611198906, -2.0794415416798357, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891, -3.871201010907891),
        (-3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.1354942159291497, -3.828641396489095, -2.4423470353692043, -1.1895840668738362, -2.4423470353692043, -3.1354942159291497, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095, -3.828641396489095),
    ),
    (
        (-4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -4.430816798843313, -2.639057329615259, -1.5976034547870974, -1.0986122886681098, -1.9459101490553135),
        (-3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -2.5257286443082556, -1.2039728043259361, -1.7147984280919266, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146, -3.912023005428146),
        (-3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006),
        (-3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -2.0476928433652555, -2.740840023925201, -2.3353749158170367, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463, -3.4339872044851463),
        (-4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -3.3843902633457743, -1.0818051703517284, -1.8803128665695, -2.1316272948504063, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572, -4.07753744390572),
    ),
    (
        (-4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.983606621708336, -4.290459441148391, -2.7863820443721172, -1.2459370034249682, -0.7069405026922811),
        (-3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -2.3608540011180215, -0.7514160886839211, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122, -3.970291913552122),
        (-3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006, -3.2188758248682006),
        (-3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -2.1972245773362196, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329, -3.295836866004329),
        (-4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -3.8815637979434374, -0.642885345779057, -2.0898043287153825, -2.176815705705012, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383, -4.574710978503383),
    ),
)
"""Default ``NetworkConfig.palette_gain_table`` (issue 16, fourth round; refitted in the
fifth; given the known colours' bin since the fourteenth): :math:`\\log p(e \\mid m, b(u))`
(block ``m``, row ``b``, column ``e + 12``) of the colours :math:`e = -12..12` a
stroke's palette has beyond the :math:`u` colours (bins ``NetworkConfig.palette_gain_bins``:
0, 1-5, 6-7, 8-9, 10 or more) of the palettes of the *known* objects of its label
(:func:`models.jorge.labels.known_objects`: not born at the stroke, and born alone, or with
their whole cohort in the label, or seen alone since: :meth:`LabelGraph.palette_stroke`),
:math:`m = 0..5` the label's other objects (block ``m``);
add-one smoothed frequencies from :func:`models.jorge.fit.fit_parameters` on the declared
training split (seeds 100-109). It is the palette evidence given the objects a label names,
so the strokes of one group, which all show its palette, do not multiply one count's
evidence. The search (:data:`models.jorge.fit.SEARCH_GRID`, scored with seeds 100-104)
keeps it, alone and with ``size_once``: training error 0.2771 against 0.2863 for the
marginal count table (:data:`FITTED_PALETTE_COUNTS`, the third round's default); refitted in
the fifth round, 0.2772 against 0.2856; refitted in the tenth, where a joiner (a newcomer
inside an inherited label) counts as known only with everyone of its birth stroke, as the
network now sees it (:meth:`LabelGraph.freeze`). Measured afterwards with the benchmark's seeds 0-4
(validation and SIMULATED meetings, never used to choose): validation 0.185 against 0.188;
SIMULATED meetings (10 scenes per k, stroke seeds 0-4) 3+ error 0.31 / 0.33 / 0.62 against
0.36 / 0.49 / 0.74 and all strokes 0.10 / 0.10 / 0.22 against 0.13 / 0.15 / 0.29 for
k = 3 / 4 / 5 (fifth round: validation 0.185; meetings 3+ 0.31 / 0.33 / 0.63, all 0.10 /
0.10 / 0.22). Before the cohort ids (third round) each object of a new group was credited
with the whole group's palette. Refitted in the sixth round under the merge test of the
link rule, which the search keeps (see :data:`FITTED_LABELS`). Conditioned on the known
colours in the fourteenth round, alone (``palette_count_table`` off) and with tentative
joiners (``OnlineConfig.tentative_joiners``): the plain :math:`p(e \\mid m)` is loose (one
newcomer with nothing known adds 5 colours in 97% of the training strokes, one with 10-12
colours known adds none in 56%), and the marginal count table covered for it by counting
the colours twice. Chosen by a comparison declared before it ran
(:data:`models.jorge.fit.CONFIRM_SEEDS`): over the scoring sets of seeds 100-104 and
125-144 (25 sets, each weighing the same) 0.2037 against 0.2206 for the thirteenth
round's default, paired difference -0.0169 (one standard error 0.0051), lower on 19 of
the 25 sets; on the scoring seeds alone 0.2007 against 0.1926. Refitted in the fifteenth
round under the merge cover test of the link rule (``NetworkConfig.merge_cover``), which
changes which strokes count as merges (see :data:`FITTED_LABELS`)."""


@dataclass(frozen=True)
class NetworkConfig:
    """Structure, CPD and colour-model settings of the label network.

    Attributes
    ----------
    v_max : float
        Maximum speed through a gap, pixels per frame.
    radius : float
        Slack in pixels added to ``v_max * gap`` (region centres jump at merges/splits).
        ``v_max = 1`` and ``radius = 30`` were chosen by labelling error on CAVIAR ground
        truth with held-out simulation seeds 20-39 (the benchmark uses 0-4) and checked on
        :mod:`models.jorge.simulate` sequences; the earlier 2.5 / 20 let links from a
        neighbour take a stroke's parent slots and missed real links (a larger slack
        than 30 brings the neighbours back).
    max_gap_frames : int
        Longest gap between a parent's end and a child's start.
    max_parents, max_children : int
        At most 2 each (seed 004, sec. 4).
    sibling_window : int
        A stroke can become the second child of a parent only if it starts within this
        many frames of the parent's end (both children are the parts of one split);
        otherwise every stroke would stay a candidate parent until it had two children.
    labels : LabelParams
        :math:`P_{new}, P_{merge}, P_{split}` and the maximum group size.
    colour_mode : {"hyper", "ratio", "eq6"}
        Colour model (see :func:`models.jorge.labels.colour_log_likelihood`); default
        ``"hyper"``: the likelihood ratio against chance matches of distinct colours.
    match_prob : float
        :math:`P` of eq. 6.
    pool_size : int
        Number of colours in the pool.
    size_evidence : bool
        Also use the stroke's region size as soft evidence on the number of people of
        its label (:func:`models.jorge.labels.size_log_likelihood`; our addition, not in
        seed 004). Needs ``Stroke.extent`` (recorded by
        :func:`models.jorge.strokes.build_strokes`); strokes without it get none.
    size_mu_single, size_slope, size_sigma : float
        mu_1, beta and sigma of the size likelihood (fitted by
        :func:`models.jorge.fit.fit_parameters` on the training split).
    size_reference_quantile : float
        The reference "one person's size" is this quantile of the log areas of all the
        strokes seen so far (recomputed as strokes arrive: on line, observable). The
        median (0.5) is pulled up where groups are common (a sequence where one pair
        walks together most of the time); a lower quantile stands for single people.
        The median is kept: on the fit sets the quantile 0.25 tells more about a
        stroke's number of people, but it did not lower the labelling error on fresh
        training-side seeds (issue 16's twentieth round, :data:`models.jorge.fit.CONFIRM_SEEDS`).
    size_min_reference : int
        No size evidence until this many other strokes have been seen.
    size_reference_neighbours : int
        The reference is taken over this many strokes nearest in image height (0: all).
    palette_count_table : tuple of tuple of float
        :math:`\\log p(c \\mid k)`, rows ``k = 1..`` people, columns ``c = 0..pool_size``
        distinct colours of the stroke's palette (the last row and column stand for
        that many or more) (:func:`models.jorge.labels.palette_count_log_likelihood`; our addition, issue 16);
        fitted by :func:`models.jorge.fit.fit_parameters` (:data:`FITTED_PALETTE_COUNTS`);
        default ``()``, none: since issue 16's fourteenth round the gain table given the
        colours already known (``palette_gain_bins``) holds the count evidence alone
        (beside the gain table from the tenth to the thirteenth round, ``()`` from the
        fourth to the ninth).
    gate : {"pixels", "scaled", "boxes"}
        Link gate. ``"pixels"``: ``radius`` + ``v_max`` * gap in pixels and frames (values
        chosen on CAVIAR, 384x288 at 25 fps: they do not carry over to other image sizes
        and frame rates). ``"scaled"``: the same in units of the parent region's size
        (median square root of its box area) and seconds, ``radius_scaled`` +
        ``v_max_scaled`` * gap_s, with ``max_gap_frames`` and ``sibling_window`` read
        at 25 fps; 1.2 and 1.0 are the CAVIAR values in those units (people there are
        about 25 px in that size and walk about 25 px per second). ``"boxes"`` (issue
        16): the scaled gate and, where both regions have boxes, the new stroke's first
        box must meet the earlier stroke's last box grown by ``v_box`` * gap_s region
        sizes on every side (``LabelGraph._boxes_near``): in crowds it keeps split parts
        and merges and drops the neighbours the centre distance let in (true
        predecessors recovered on the training split, seed 100: PETS2009 S1L1-2
        0.51 -> 0.66, S1L2-2 0.48 -> 0.64, CAVIAR 0.72-0.94 -> 0.85-0.98).
    v_box : float
        Region sizes per second the last box grows by in the ``"boxes"`` gate.
    palette_gain_table : tuple of tuple of float, or tuple of tuple of tuple of float
        :math:`\\log p(e \\mid m, b(u))` of the colours :math:`e` a label's ``m`` objects
        born at the stroke add to the :math:`u` colours of its known objects' palettes,
        shape ``(max_m + 1, len(palette_gain_bins), 2 * pool_size + 1)``, columns ``e =
        -pool_size .. pool_size``; a 2-D table ``(max_m + 1, 2 * pool_size + 1)`` is
        :math:`\\log p(e \\mid m)` (the fourth to thirteenth rounds') and ignores the bins
        (:func:`models.jorge.labels.palette_gain_log_likelihood`; issue 16). Added to the
        ``palette_count_table`` evidence when both are set; fitted by
        :func:`models.jorge.fit.fit_parameters`; default :data:`FITTED_PALETTE_GAINS`;
        ``()``: none.
    palette_gain_bins : tuple of int
        Lower edges of the bins of :math:`u` a 3-D ``palette_gain_table`` is conditioned
        on: 0, 1-5, 6-7, 8-9, 10 or more known colours (one person's palette holds 5;
        fixed in issue 16's thirteenth round, before the comparison that chose the table).
    size_once : bool
        No size evidence at an OCCLUSION node (one parent that does not split): the same
        region continued, whose size was counted at its parent. The strokes of one region
        measure one size, with one error (a person near the camera stays large), so summing
        their size evidence as independent over-counts it: with new groups on, a single
        person near the camera was labelled a new group of three or four after a few
        strokes (issue 16 diagnosis, ``models.jorge.fit``). On by default from the fourth
        to the tenth round (the search's choice); off in the eleventh, when the search
        over ``palette_continued`` chose the size counted at every stroke beside palette
        counts weighed 0.5 where a region continues; on again since the twelfth, the
        search's choice with nested links (:data:`FITTED_LABELS`, twelfth round).
    truncate_pruned : bool
        A child's CPD rows over a pruned domain keep the probabilities of the unpruned
        model (rows sum to what the pruning kept, :func:`models.jorge.labels.child_table`
        with ``truncate``; in a window the row is normalised and the kept mass enters as an
        observed binary node ``m{k}``, :func:`kept_name`), so the window's joint is the
        unpruned joint restricted to the kept labels. False: each row renormalised over the
        kept labels (before issue 16's fourth round), which lets a wrong parent label whose
        children's right labels were pruned put all their mass on :math:`l_{new}`.
    merge_area : float
        Merge test of the link rule (issue 16, sixth round; 0: off). A merged region holds
        the people of both its parents, so its box is at least as large as each parent's:
        two candidate parents are both linked only if the new stroke's first box has at
        least ``merge_area`` times the area of each parent's last box; otherwise only the
        nearest is. 1 (default, the search's choice) is the geometric bound, not a fitted
        value. Strokes without boxes are not tested. On the training split (seeds
        100-102) it keeps 98% (PETS2009 S1 crowds) and 100% (CAVIAR) of the two-parent
        sets whose both links are true and drops 79% / 60% of those with a spurious
        parent; link accuracy (seeds 100-104) 0.65 -> 0.69 and 0.57 -> 0.72 in the
        crowds, 0.90-0.93 -> 0.95-0.97 on CAVIAR.
    palette_continued : float
        Weight of the palette colour-count evidence (:meth:`palette_count_loglik`: the
        count table and the gain table) at an OCCLUSION node, the same region continued
        (issue 16, eleventh round): its colours were counted at the parent too, and the
        counts of one region's strokes are not independent, so summing them in full
        over-counts them, as the region size was before ``size_once`` (a group standing
        together for many strokes was pulled to one person more or less than it held).
        1: full weight (before the eleventh round); 0: none. A dimension of the
        documented search (:data:`models.jorge.fit.SEARCH_GRID`), which chose 0.5 in the
        eleventh round and 0.75 with nested links (:data:`FITTED_LABELS`, twelfth round).
    chain_palette : bool
        A person whose palette is not yet their own (a member of a new group or a joiner,
        whose birth palette holds the others' colours too) and who continues alone from a
        parent stroke labelled that person alone is matched against the parent stroke's
        palette: their latest view alone (issue 16, eleventh round; our addition). Without
        it, the palette becomes theirs only once a stroke alone is frozen
        (:meth:`LabelGraph.freeze`), so inside the window "the member who left the group"
        was scored on the group's palette stroke after stroke, while "a new object born
        when the member left" was scored on its own first stroke: a member leaving a group
        was labelled a newcomer and the member vanished. A factor over the parent's and
        the child's labels (:meth:`LabelGraph.chain_log_ratio`): in the window it is folded
        into the child's CPD rows, each row's scale carried by the observed node
        :func:`kept_name` (as the pruned mass is). On by default: on the
        search's scoring sets (training sequences plus SIMULATED meetings, seeds
        100-104, :func:`models.jorge.fit.scoring_groups`) the combined error fell from
        0.2052 to 0.2024 (per seed 0.2175, 0.2204, 0.2159, 0.1731, 0.1991 -> 0.2175,
        0.2109, 0.2114, 0.1731, 0.1991: no seed worse; 1.5 standard errors of the paired
        differences, the search's rule). The same for every person alone (a lone
        newcomer's own birth palette replaced by its latest view) was worse, 0.2201
        (ms3ggt 0.015 -> 0.127): a palette seen alone is kept.
    nested_links : float
        Nested links of the link rule (issue 16, twelfth round; our addition; 0: off). A
        candidate parent ``a`` is superseded by its descendant candidates (the new stroke
        continues them), except when its only child ``c`` looks like a part of it (``a``'s
        last box at least ``nested_links`` times the area of ``c``'s first box) and the
        new stroke's first box passes the merge test against ``c``'s last: then both are
        linked. It is a member seen alone for a moment while the rest of the group was
        hidden, and the new stroke is the group again (the rest merging back with ``c``)
        or the rest alone (``c``'s sibling). Without it the group came back as ``c``'s
        label or ``c`` plus a newcomer, and the error was carried along the group's
        strokes. The restriction between ``c`` and the new stroke, two children of ``a``,
        then admits ``c`` inside the new stroke
        (:func:`models.jorge.labels.restriction_allows`, nested). 2 was chosen among 1.5,
        2 and 3 on the search's scoring sets (:data:`FITTED_LABELS`, twelfth round).
    merge_cover : float
        Cover test of the link rule's merge test (issue 16, fifteenth round; our addition;
        0: off). A merged region covers both its parts, so two candidate parents are both
        linked only if the new stroke's first box covers at least ``merge_cover`` of each
        parent's last box, grown by the box gate's slack (``v_box`` times the parent's
        scale times the seconds of the gap); otherwise only the nearest is. The area test
        alone let a neighbour whose box merely touched a region of two people's size
        become a second parent; that spurious merge then put the neighbour's person in the
        region and in every stroke after it. On training-side data (the training
        sequences with seeds 105-109 and SIMULATED meetings of 3-5 people, scenes
        105-124), among the two-parent links the area test passes, the least share
        covered is at least 0.17 for every true merge (0.38 for 95% of them) and below 0.1
        for half of the spurious ones; the number of links that differ from the true links
        is least at 0.2 (584 without the test; 524 / 513 / 509 / 511 / 517 / 529 at 0.1 /
        0.15 / 0.2 / 0.25 / 0.3 / 0.4), so 0.2, chosen on link counts before any labelling
        run. With the parameters refitted under it, on the search's scoring sets (seeds
        100-104) pooled with the same sets of fresh seeds 165-184 (recorded with
        :data:`models.jorge.fit.CONFIRM_SEEDS`; a comparison declared before it ran) the
        combined error fell from 0.2014 to 0.1987 (paired -0.0027, standard error 0.0026,
        lower on 19 of 25 sets). It holds with or without the area test (``merge_area``
        0), and in the nested links' test (``nested_links``). Strokes without boxes are
        not tested.
    """

    v_max: float = 1.0
    radius: float = 30.0
    max_gap_frames: int = 30
    max_parents: int = 2
    max_children: int = 2
    sibling_window: int = 20
    labels: LabelParams = field(default_factory=lambda: FITTED_LABELS)
    colour_mode: str = "hyper"
    match_prob: float = 0.8
    pool_size: int = 12
    size_evidence: bool = True
    size_mu_single: float = -0.32198974081239023
    size_slope: float = 0.654945292255393
    size_sigma: float = 0.6665794021592003
    size_reference_quantile: float = 0.5
    size_min_reference: int = 1
    size_reference_neighbours: int = 0
    gate: str = "boxes"
    palette_count_table: tuple = ()
    radius_scaled: float = 1.2
    v_max_scaled: float = 1.0
    v_box: float = 0.5
    palette_gain_table: tuple = FITTED_PALETTE_GAINS
    palette_gain_bins: tuple = (0, 1, 6, 8, 10)
    size_once: bool = True
    truncate_pruned: bool = True
    merge_area: float = 1.0
    palette_continued: float = 0.75
    chain_palette: bool = True
    nested_links: float = 2.0
    merge_cover: float = 0.2

    def __post_init__(self) -> None:
        if self.v_max <= 0 or not np.isfinite(self.v_max):
            raise ModelError(f"NetworkConfig.v_max must be > 0, got {self.v_max}")
        if self.radius < 0:
            raise ModelError(f"NetworkConfig.radius must be >= 0, got {self.radius}")
        if self.max_gap_frames < 1:
            raise ModelError(f"NetworkConfig.max_gap_frames must be >= 1, got {self.max_gap_frames}")
        if not 1 <= self.max_parents <= 2 or not 1 <= self.max_children <= 2:
            raise ModelError(
                "NetworkConfig: at most 2 parents and 2 children per node (seed 004), got "
                f"{self.max_parents} / {self.max_children}"
            )
        if self.gate not in ("pixels", "scaled", "boxes"):
            raise ModelError(f"NetworkConfig.gate must be 'pixels', 'scaled' or 'boxes', got {self.gate!r}")
        if not self.v_box >= 0:
            raise ModelError(f"NetworkConfig.v_box must be >= 0, got {self.v_box}")
        if not 0.0 <= self.palette_continued <= 1.0:
            raise ModelError(f"NetworkConfig.palette_continued must be in [0, 1], got {self.palette_continued}")
        if not (self.merge_area >= 0 and np.isfinite(self.merge_area)):
            raise ModelError(f"NetworkConfig.merge_area must be finite and >= 0, got {self.merge_area}")
        if not 0 <= self.merge_cover <= 1:
            raise ModelError(f"NetworkConfig.merge_cover must be in [0, 1], got {self.merge_cover}")
        if not self.radius_scaled >= 0 or not self.v_max_scaled > 0:
            raise ModelError(
                f"NetworkConfig: radius_scaled must be >= 0 and v_max_scaled > 0, got "
                f"{self.radius_scaled} / {self.v_max_scaled}"
            )
        if self.palette_count_table:
            t = np.asarray(self.palette_count_table, dtype=np.float64)
            if t.ndim != 2 or t.shape[1] < 2 or not np.all(t <= 0):
                raise ModelError(
                    f"NetworkConfig.palette_count_table must be a 2-D table of log "
                    f"probabilities (max_k, max_count + 1), got shape {t.shape}"
                )
        bins = np.asarray(self.palette_gain_bins)
        if not gain_bins_rise(bins):
            raise ModelError(f"NetworkConfig.palette_gain_bins must rise from 0, got {self.palette_gain_bins}")
        if self.palette_gain_table:
            t = np.asarray(self.palette_gain_table, dtype=np.float64)
            if t.ndim not in (2, 3) or t.shape[-1] % 2 != 1 or not np.all(t <= 0) or (
                    t.ndim == 3 and t.shape[1] != bins.size):
                raise ModelError(
                    f"NetworkConfig.palette_gain_table must be a table of log probabilities "
                    f"(max_new + 1, [{bins.size} bins of palette_gain_bins,] 2 * pool_size + 1), "
                    f"got shape {t.shape}"
                )
        if self.colour_mode not in ("ratio", "hyper", "eq6"):
            raise ModelError(
                f"NetworkConfig.colour_mode must be 'hyper', 'ratio' or 'eq6', got {self.colour_mode!r}"
            )
        if not 0.0 < self.match_prob < 1.0:
            raise ModelError(f"NetworkConfig.match_prob must be in (0, 1), got {self.match_prob}")
        if not self.size_sigma > 0 or not np.isfinite(self.size_sigma):
            raise ModelError(f"NetworkConfig.size_sigma must be > 0, got {self.size_sigma}")
        if not np.isfinite(self.size_mu_single) or not np.isfinite(self.size_slope):
            raise ModelError(
                f"NetworkConfig.size_mu_single / size_slope must be finite, got "
                f"{self.size_mu_single} / {self.size_slope}"
            )


@dataclass
class _Node:
    stroke: Stroke
    parents: tuple[int, ...]
    children: list[int]
    domain: tuple[Label, ...]
    frozen: Label | None = None
    rel_log_area: float = float("nan")


class LabelGraph:
    """The growing graph of strokes, links and label domains (seed 004, secs. 4-5).

    Strokes are added in start order (:meth:`add_stroke`); each new node gets its parents
    among the strokes that ended before it started and its admissible labels from its
    parents' current domains. Nodes can be frozen to one label (:meth:`freeze`) and
    domains pruned (:meth:`set_domain`); :meth:`window` turns a set of active nodes into a
    :class:`WindowNet` for exact inference.

    Parameters
    ----------
    config : NetworkConfig
    with_domains : bool
        Compute label domains (``False``: links only, for counting training events).
    fps : float
        Frame rate of the strokes (the ``"scaled"`` link gate works in seconds).
    """

    def __init__(self, config: NetworkConfig | None = None, with_domains: bool = True,
                 fps: float = 25.0) -> None:
        self.config = NetworkConfig() if config is None else config
        if not fps > 0:
            raise ModelError(f"LabelGraph: fps must be > 0, got {fps}")
        self.fps = float(fps)
        self.with_domains = with_domains
        self.nodes: list[_Node] = []
        n0 = 16
        self._end = np.zeros(n0, dtype=np.int64)
        self._end_pos = np.zeros((n0, 2))
        self._end_ext = np.full((n0, 2), np.nan)
        self._nchild = np.zeros(n0, dtype=np.int64)
        self._palettes = np.zeros((n0, self.config.pool_size), dtype=bool)
        self._log_area = np.full(n0, np.nan)
        self._foot_y = np.full(n0, np.nan)
        self._scale = np.full(n0, np.nan)
        self._own: dict[int, int] = {}  # member of a new group or joiner -> stroke with its own palette
        self._joiners: dict[int, Label] = {}  # joiner -> its birth label (frozen, or tentative)
        self._tentative: dict[int, list[int]] = {}  # unfrozen node -> its tentative joiners
        # unfrozen node -> what it remembers of its CPD table, colour evidence, chain ratio
        self._cpd_memo: dict[int, TableMemo] = {}
        self._evidence_memo: dict[int, EvidenceMemo] = {}
        self._chain_memo: dict[int, ChainMemo] = {}
        self._gain_table = np.asarray(self.config.palette_gain_table, dtype=np.float64)
        self._gain_bins = self.config.palette_gain_bins if self._gain_table.ndim == 3 else ()
        self._count_table = np.asarray(self.config.palette_count_table, dtype=np.float64)

    # --- growth --------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.nodes)

    def _grow(self) -> None:
        n = self._end.shape[0] * 2
        for name in ("_end", "_end_pos", "_end_ext", "_nchild", "_palettes", "_log_area", "_foot_y", "_scale"):
            old = getattr(self, name)
            new = np.full((n, *old.shape[1:]), np.nan) if name in ("_log_area", "_foot_y", "_scale", "_end_ext") else \
                np.zeros((n, *old.shape[1:]), dtype=old.dtype)
            new[: old.shape[0]] = old
            setattr(self, name, new)

    def check_stroke(self, stroke: Stroke) -> None:
        """Raise if ``stroke`` cannot be the next node (nothing is changed).

        Raises
        ------
        InputError
            Wrong index, bad colours.
        TimeOrderError
            Ends before it starts, or starts before the previous stroke.
        """
        k = len(self.nodes)
        for name in ("index", "start", "end"):
            v = getattr(stroke, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
                raise InputError(f"stroke {k}: {name} must be an int, got {v!r}")
        if stroke.index != k:
            raise InputError(f"stroke index {stroke.index}: the next stroke must have index {k}")
        if stroke.end < stroke.start:
            raise TimeOrderError(f"stroke {k}: end frame {stroke.end} is before start frame {stroke.start}")
        if self.nodes and stroke.start < self.nodes[-1].stroke.start:
            raise TimeOrderError(
                f"stroke {k} starts at frame {stroke.start}, before stroke {k - 1} "
                f"(frame {self.nodes[-1].stroke.start}): strokes must come in start order"
            )
        _check_colours(k, stroke.colours, self.config.pool_size)
        _check_palette(k, stroke.palette, self.config.pool_size)
        pos = np.asarray(stroke.positions)
        if pos.ndim != 2 or pos.shape[1] != 2 or pos.shape[0] < 1:
            raise InputError(f"stroke {k}: positions must have shape (num_points, 2), got {pos.shape}")
        if not np.issubdtype(pos.dtype, np.number) or np.iscomplexobj(pos):
            raise InputError(f"stroke {k}: positions must be real numbers, got dtype {pos.dtype}")
        if not np.all(np.isfinite(pos)) or np.any(np.abs(pos) > _MAX_PIXELS):
            raise InputError(f"stroke {k}: positions must be finite pixels, |x| <= {_MAX_PIXELS:g}")
        _check_frames(k, stroke, pos.shape[0])
        ext = getattr(stroke, "extent", None)
        if ext is not None:
            if np.iscomplexobj(ext):
                raise InputError(f"stroke {k}: extent must be real numbers")
            ext = np.asarray(ext, dtype=np.float64)
            if ext.shape != pos.shape:
                raise ShapeError(f"stroke {k}: extent must have shape {pos.shape}, got {ext.shape}")
            if not np.all(np.isfinite(ext)) or np.any(ext <= 0) or np.any(ext > _MAX_PIXELS):
                raise InputError(
                    f"stroke {k}: region extent (width, height) must be in (0, {_MAX_PIXELS:g}] pixels"
                )

    def candidate_parents(self, stroke: Stroke) -> np.ndarray:
        r"""Parents of a new stroke: ended before it starts, reachable, with a free child
        slot; at most ``max_parents``, by increasing spatial gap (seed 004, sec. 4). A
        candidate that is an ancestor of another is dropped (the new stroke continues the
        descendant), unless it is kept as a nested link (``NetworkConfig.nested_links``).

        A stroke ``i`` can precede ``j`` when
        :math:`0 < t^{start}_j - t^{end}_i \le` ``max_gap_frames`` and
        :math:`\|p^{start}_j - p^{end}_i\| \le` ``radius`` + ``v_max`` :math:`(t^{start}_j - t^{end}_i)`
        (the other gates: ``NetworkConfig.gate``). Two parents (a merge) must pass the
        merge test (``NetworkConfig.merge_area``, ``NetworkConfig.merge_cover``), else only
        the nearest is kept.

        Returns
        -------
        ndarray of int, shape (num_parents,)
            Parent stroke indices, nearest first.
        """
        n = len(self.nodes)
        if n == 0:
            return np.zeros(0, dtype=np.int64)
        cfg = self.config
        gap = stroke.start - self._end[:n]
        dist = np.linalg.norm(self._end_pos[:n] - stroke.positions[0], axis=1)
        if cfg.gate in ("scaled", "boxes"):
            # distances in units of the parent region's size, times in seconds; a parent
            # without a recorded size falls back to the pixel gate
            unit = np.where(np.isfinite(self._scale[:n]), self._scale[:n], np.nan)
            secs = gap / self.fps
            f25 = 25.0 / self.fps  # the frame limits were set at 25 fps
            reach = np.where(np.isfinite(unit), unit * (cfg.radius_scaled + cfg.v_max_scaled * secs),
                             cfg.radius + cfg.v_max * gap)
            max_gap, window = cfg.max_gap_frames / f25, cfg.sibling_window / f25
        else:
            reach = cfg.radius + cfg.v_max * gap
            max_gap, window = cfg.max_gap_frames, cfg.sibling_window
        near = dist <= reach
        if cfg.gate == "boxes":
            near = self._boxes_near(stroke, self._box_slack(stroke, slice(0, n)), near)
        ok = (gap > 0) & (gap <= max_gap) & near
        ok &= self._nchild[:n] < cfg.max_children
        # a second child (the other part of a split) must start within ``sibling_window``
        # frames of the parent's end
        ok &= (self._nchild[:n] == 0) | (gap <= window)
        cand = np.flatnonzero(ok)
        # a candidate that is an ancestor of another candidate is superseded by it (the
        # new stroke continues the descendant, it is not its sibling)
        cset = set(cand.tolist())
        superseded = {a for c in cand.tolist() for a in self._ancestors(c, 3) if a in cset}
        back = {a for a in superseded if self._merges_back(stroke, a, cset)} if cfg.nested_links > 0 else set()
        cand = np.array([c for c in cand.tolist() if c not in superseded - back], dtype=np.int64)
        order = np.lexsort((cand, dist[cand]))
        cand = cand[order][: cfg.max_parents]
        # a nested pair passed its own merge test in _merges_back
        nested = len(cand) == 2 and self.nested(*sorted(int(c) for c in cand))
        if len(cand) == 2 and not nested and not self._merge_fits(stroke, cand):
            cand = cand[:1]
        return cand

    def _merges_back(self, stroke: Stroke, a: int, cset: set) -> bool:
        """Nested link (``NetworkConfig.nested_links``): candidate ``a``, superseded by its
        only child ``c`` (also a candidate), stays a parent of the new stroke when ``c``
        looks like a part of ``a`` (``a``'s last box at least ``nested_links`` times the
        area of ``c``'s first) and the new stroke's first box passes the merge test
        against ``c``'s last box: the new stroke is the rest of ``a``, alone or merging
        back with ``c`` (issue 16, twelfth round)."""
        kids = self.nodes[a].children
        if len(kids) != 1 or kids[0] not in cset:
            return False
        c = kids[0]
        first = getattr(self.nodes[c].stroke, "extent", None)
        if first is None or not np.all(np.isfinite(self._end_ext[a])):
            return False
        part = float(np.prod(self._end_ext[a])) >= self.config.nested_links * float(np.prod(first[0]))
        return part and self._merge_fits(stroke, np.array([c]))

    def _merge_fits(self, stroke: Stroke, parents: np.ndarray) -> bool:
        """Merge test (``NetworkConfig.merge_area``, ``merge_cover``): the new stroke's
        first box has at least ``merge_area`` times the area of each parent's last box,
        and covers at least ``merge_cover`` of each parent's last box grown by the box
        gate's slack (True where a box is unknown)."""
        ext = getattr(stroke, "extent", None)
        areas = np.prod(self._end_ext[parents], axis=1)
        if ext is None or not np.all(np.isfinite(areas)):
            return True
        if not np.all(float(np.prod(ext[0])) >= self.config.merge_area * areas):
            return False
        return self.config.merge_cover <= 0 or bool(np.all(self._cover(stroke, parents) >= self.config.merge_cover))

    def _cover(self, stroke: Stroke, parents: np.ndarray) -> np.ndarray:
        r"""Share of each parent's last box, grown by the box gate's slack
        (:meth:`_box_slack`), inside the new stroke's first box; shape ``(len(parents),)``.
        A merged region covers both its parts; a neighbour that only touches it does not."""
        half = 0.5 * stroke.extent[0]
        lo, hi = stroke.positions[0] - half, stroke.positions[0] + half
        slack = np.nan_to_num(self._box_slack(stroke, parents))[:, None]
        plo = self._end_pos[parents] - 0.5 * self._end_ext[parents] - slack
        phi = self._end_pos[parents] + 0.5 * self._end_ext[parents] + slack
        inter = np.prod(np.clip(np.minimum(hi, phi) - np.maximum(lo, plo), 0.0, None), axis=1)
        return inter / np.prod(phi - plo, axis=1)

    def _box_slack(self, stroke: Stroke, idx) -> np.ndarray:
        """The box gate's slack in pixels for earlier strokes ``idx``: ``v_box`` times each
        one's scale (NaN where it has no boxes) times the seconds from its end to the new
        stroke's start."""
        return self._scale[idx] * self.config.v_box * (stroke.start - self._end[idx]) / self.fps

    def _boxes_near(self, stroke: Stroke, slack: np.ndarray, fallback: np.ndarray) -> np.ndarray:
        """Box gate: the new stroke's first region box meets each earlier stroke's last
        box grown by ``slack`` pixels on every side (shape ``(n,)``); where either box is
        unknown, ``fallback`` (the centre-distance gate).

        A split part's box lies inside its group's last box and a merged region's box
        covers its parts', wherever their centres are, while a neighbour's box in a crowd
        is apart from it: the gate admits the first two and not the third.
        """
        ext = getattr(stroke, "extent", None)
        n = len(self.nodes)
        if ext is None:
            return fallback
        sep = np.abs(self._end_pos[:n] - stroke.positions[0]) - 0.5 * (self._end_ext[:n] + ext[0])
        with np.errstate(invalid="ignore"):
            meets = np.all(sep <= slack[:, None], axis=1)
        known = np.all(np.isfinite(self._end_ext[:n]), axis=1) & np.isfinite(slack)
        return np.where(known, meets, fallback)

    def _ancestors(self, k: int, depth: int) -> set[int]:
        out: set[int] = set()
        front = set(self.nodes[k].parents)
        for _ in range(depth):
            out |= front
            front = {p for f in front for p in self.nodes[f].parents} - out
        return out

    def check_links(self, stroke: Stroke, parents: Iterable[int]) -> tuple[int, ...]:
        """Validate links given for a new stroke instead of :meth:`candidate_parents`
        (from a low-level tracker that reports its merges and splits, or the true
        predecessors as an oracle); nothing changes.

        Parameters
        ----------
        stroke : Stroke
            The next stroke (index ``len(self)``).
        parents : iterable of int
            Indices of earlier strokes, at most ``max_parents``, distinct, each ended
            before ``stroke.start`` and with fewer than ``max_children`` children.

        Returns
        -------
        tuple of int
            The parents, sorted.

        Raises
        ------
        InputError
            A parent that is not an earlier stroke, repeated, not ended before the stroke
            starts, already with ``max_children`` children, or too many parents.
        """
        k = len(self.nodes)
        try:
            links = [operator.index(p) for p in parents]
        except TypeError as err:
            raise InputError(f"stroke {k}: parents must be stroke indices (ints), got {parents!r}") from err
        cfg = self.config
        if len(set(links)) != len(links) or len(links) > cfg.max_parents:
            raise InputError(f"stroke {k}: parents {links} must be distinct and at most "
                             f"max_parents={cfg.max_parents}")
        for p in links:
            if not 0 <= p < k:
                raise InputError(f"stroke {k}: parent {p} is not an earlier stroke (0..{k - 1})")
            if self._end[p] >= stroke.start:
                raise InputError(f"stroke {k}: parent {p} ends at frame {self._end[p]}, not before "
                                 f"the stroke starts (frame {stroke.start})")
            if self._nchild[p] >= cfg.max_children:
                raise InputError(f"stroke {k}: parent {p} already has max_children="
                                 f"{cfg.max_children} children")
        return tuple(sorted(links))

    def add_stroke(self, stroke: Stroke, parents: Iterable[int] | None = None, *,
                   checked: bool = False) -> tuple[int, list[int]]:
        """Add the node of a new stroke (validated first: nothing changes on error).

        Parameters
        ----------
        stroke : Stroke
            The next stroke, in start order.
        parents : iterable of int, optional
            Its links, checked by :meth:`check_links`; ``None`` (default): the on-line
            link rule, :meth:`candidate_parents`.
        checked : bool
            The caller has just run :meth:`check_stroke` on ``stroke`` and, if given,
            ``parents`` is what :meth:`check_links` returned for it: not checked again.

        Returns
        -------
        k : int
            The node index (= stroke index).
        widened : list of int
            Earlier children of the new node's parents whose domain grew because their
            parent now splits (eq. 9).
        """
        if not checked:
            self.check_stroke(stroke)
        k = len(self.nodes)
        if parents is None:
            parents = tuple(int(p) for p in sorted(self.candidate_parents(stroke)))
        elif not checked:
            parents = self.check_links(stroke, parents)
        if k >= self._end.shape[0]:
            self._grow()
        self._end[k] = stroke.end
        self._end_pos[k] = stroke.positions[-1]
        self._palettes[k, stroke.palette] = True
        rel = float("nan")
        ext = getattr(stroke, "extent", None)
        if ext is not None:
            self._log_area[k] = float(np.median(np.log(ext[:, 0] * ext[:, 1])))
            self._foot_y[k] = float(np.median(stroke.positions[:, 1] + ext[:, 1] / 2))
            self._scale[k] = float(np.median(np.sqrt(ext[:, 0] * ext[:, 1])))
            self._end_ext[k] = ext[-1]
        for p in parents:
            self._nchild[p] += 1
            self.nodes[p].children.append(k)
        node = _Node(stroke, parents, [], (), rel_log_area=rel)
        self.nodes.append(node)
        node.rel_log_area = self.rel_log_area(k)  # as seen when the stroke starts
        if not self.with_domains:
            return k, []
        node.domain = self._admissible(k)
        # a parent that now splits changes its other child's structure: widen that domain
        widened = []
        for p in parents:
            for c in self.nodes[p].children:
                if c != k and self.nodes[c].frozen is None and len(self.nodes[p].children) == 2:
                    wider = self._admissible(c)
                    have = set(self.nodes[c].domain)
                    extra = [lab for lab in wider if lab not in have]
                    if extra:
                        self.nodes[c].domain = tuple(self.nodes[c].domain) + tuple(extra)
                        widened.append(c)
        return k, widened

    # --- accessors -----------------------------------------------------------------------
    def parent_domains(self, k: int) -> list[tuple[Label, ...]]:
        """Current domains of node ``k``'s parents (a frozen parent: its label alone)."""
        return [self.current_domain(p) for p in self.nodes[k].parents]

    def nested(self, i: int, j: int) -> bool:
        """Whether node ``i`` (``i < j``) is a parent of node ``j``: two siblings in a nested
        link (``NetworkConfig.nested_links``; :func:`models.jorge.labels.restriction_allows`)."""
        return i in self.nodes[j].parents

    def cover_parent(self, i: int, j: int) -> int | None:
        """The group whose split the restriction node of siblings ``i < j`` weighs with
        ``LabelParams.split_cover`` (:func:`models.jorge.labels.restriction_table`): their one
        shared parent, if the option is on and the link is not nested; else None."""
        if not len(self.config.labels.split_cover) or self.nested(i, j):
            return None
        shared = set(self.nodes[i].parents) & set(self.nodes[j].parents)
        return min(shared) if len(shared) == 1 else None

    def shared(self, k: int) -> list[bool]:
        """For each parent of ``k``: whether it has a second child."""
        return [len(self.nodes[p].children) >= 2 for p in self.nodes[k].parents]

    def current_domain(self, k: int) -> tuple[Label, ...]:
        """The node's domain, or its frozen label alone."""
        node = self.nodes[k]
        return (node.frozen,) if node.frozen is not None else node.domain

    def structure(self, k: int) -> str:
        """Basic structure (fig. 3) of node ``k``."""
        return structure_of(len(self.nodes[k].parents), self.shared(k))

    def siblings(self, k: int) -> list[int]:
        """Other children of ``k``'s parents."""
        out = []
        for p in self.nodes[k].parents:
            out += [c for c in self.nodes[p].children if c != k and c not in out]
        return out

    def _admissible(self, k: int) -> tuple[Label, ...]:
        return tuple(
            admissible_labels(self.parent_domains(k), self.shared(k), frozenset({k}),
                              self.config.labels.max_group_size, self.config.labels.p_part > 0,
                              max_new=self._max_new(k),
                              join=self.config.labels.p_join > 0)
        )

    def _max_new(self, k: int) -> int:
        labels = self.config.labels
        return len(labels.new_group_probs) if labels.child_new_groups or not self.nodes[k].parents else 1

    def palette_stroke(self, o: int) -> int:
        """The stroke whose palette object ``o`` has: its birth stroke (sec. 4.1), or for a
        member of a new group or a joiner the first stroke frozen to it alone
        (:meth:`freeze`), once there is one."""
        return self._own.get(int(o), birth_stroke(o))

    def palettes(self, domain: Sequence[Label]) -> np.ndarray:
        """Palette of each label: the union of its objects' palettes
        (:meth:`palette_stroke`; the members of a new group share their birth stroke's
        palette until one is frozen alone).

        Returns
        -------
        ndarray of bool, shape (num_labels, pool_size)
        """
        obj = label_objects(domain, -1, self._own, self._joiners)
        return union_rows(self._palettes, obj.palette_strokes, obj.sizes)

    def colour_loglik(self, k: int, domain: Sequence[Label] | None = None, mode: str | None = None,
                      objects: LabelObjects | None = None) -> np.ndarray:
        """Colour log-likelihood of stroke ``k`` for each label of ``domain`` (eq. 6);
        ``objects``: :func:`models.jorge.labels.label_objects` of ``domain`` at ``k`` if
        already computed.

        Returns
        -------
        ndarray, shape (num_labels,)
        """
        domain = self.nodes[k].domain if domain is None else domain
        obj = label_objects(domain, k, self._own, self._joiners) if objects is None else objects
        # a new label's palette comes from this stroke itself (seed 004, sec. 4.1)
        # (``Stroke.palette``): a label holding an object born here (a new group, or an
        # inherited label joined by a newcomer) gets no colour evidence (ratio 1)
        return colour_log_likelihood(
            self.nodes[k].stroke.colours, union_rows(self._palettes, obj.palette_strokes, obj.sizes),
            obj.is_new, self.config.match_prob, self.config.pool_size,
            self.config.colour_mode if mode is None else mode,
        )

    def rel_log_area(self, k: int) -> float:
        """Log area of stroke ``k``'s region minus the reference: the
        ``size_reference_quantile`` of the log areas of the ``size_reference_neighbours``
        strokes seen so far whose region's bottom edge (the feet, on the ground plane) is
        nearest in image height to stroke ``k``'s (itself included; people nearer the
        camera are larger). NaN: no recorded size, or fewer than ``size_min_reference``
        others."""
        n = len(self.nodes)
        own = self._log_area[k]
        if not np.isfinite(own):
            return float("nan")
        ok = np.flatnonzero(np.isfinite(self._log_area[:n]))
        if ok.size - 1 < self.config.size_min_reference:
            return float("nan")
        m = self.config.size_reference_neighbours
        if 0 < m < ok.size:
            near = np.argpartition(np.abs(self._foot_y[ok] - self._foot_y[k]), m - 1)[:m]
            ok = ok[near]
        return float(own - _linear_quantile(self._log_area[ok], self.config.size_reference_quantile))

    def size_loglik(self, k: int, domain: Sequence[Label] | None = None) -> np.ndarray:
        """Region-size log-likelihood of stroke ``k`` for each label of ``domain``
        (:func:`models.jorge.labels.size_log_likelihood`; zeros when ``size_evidence`` is
        off or the stroke has no recorded extent).

        Returns
        -------
        ndarray, shape (num_labels,)
        """
        domain = self.nodes[k].domain if domain is None else domain
        cfg = self.config
        rel = self.rel_log_area(k) if cfg.size_evidence else float("nan")
        if cfg.size_once and self.structure(k) == "OCCLUSION":
            rel = float("nan")  # the same region continued: its size was counted at the parent
        sizes = np.array([len(lab) for lab in domain], dtype=np.int64)
        return size_log_likelihood(rel, sizes, cfg.size_mu_single, cfg.size_slope, cfg.size_sigma)

    def palette_count_loglik(self, k: int, domain: Sequence[Label] | None = None,
                             objects: LabelObjects | None = None) -> np.ndarray:
        """Palette colour-count log-likelihood of stroke ``k`` for each label of ``domain``:
        the marginal :math:`\\log p(c \\mid k)` with ``palette_count_table``
        (:func:`models.jorge.labels.palette_count_log_likelihood`) plus, with
        ``palette_gain_table`` (the default, alone), the gain given the known objects'
        palettes (:func:`models.jorge.labels.palette_gain_log_likelihood`, in the bin of
        ``palette_gain_bins`` of the colours they hold for a 3-D table); zeros without
        either; times ``palette_continued`` at an OCCLUSION node.

        Returns
        -------
        ndarray, shape (num_labels,)
        """
        domain = self.nodes[k].domain if domain is None else domain
        count = int(np.unique(self.nodes[k].stroke.palette).size)
        sizes = np.array([len(lab) for lab in domain], dtype=np.int64)
        out = palette_count_log_likelihood(count, sizes, self._count_table)
        if self._gain_table.size:
            obj = label_objects(domain, k, self._own, self._joiners) if objects is None else objects
            u = union_rows(self._palettes, obj.known_strokes, obj.known_counts).sum(axis=1)
            out = out + palette_gain_log_likelihood(count, u, sizes - obj.known_counts,
                                                    self._gain_table, self._gain_bins)
        return self._palette_weight(k) * out

    def _palette_weight(self, k: int) -> float:
        """``palette_continued`` at an OCCLUSION node (the same region continued), else 1."""
        w = self.config.palette_continued
        return w if w != 1.0 and self.structure(k) == "OCCLUSION" else 1.0

    def evidence_loglik(self, k: int, domain: Sequence[Label] | None = None) -> np.ndarray:
        """All soft evidence of stroke ``k`` per label: colours (eq. 6, default mode) plus
        region size (:meth:`size_loglik`) plus palette colour count
        (:meth:`palette_count_loglik`).

        Returns
        -------
        ndarray, shape (num_labels,)
        """
        domain = self.nodes[k].domain if domain is None else domain
        colour, palette = self._colour_and_palette_loglik(k, tuple(domain))
        return colour + self.size_loglik(k, domain) + palette

    def _colour_and_palette_loglik(self, k: int, domain: tuple[Label, ...]) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`colour_loglik` and :meth:`palette_count_loglik` of ``k`` over ``domain``,
        read off the node's :class:`~models.jorge.memo.EvidenceMemo` where it holds them
        (same config and structure, every label remembered, the same palette records for
        their objects), else computed and remembered. The size evidence is not
        remembered: its reference grows with every stroke. Each shape (len(domain),)."""
        records = self._palette_records(domain)
        structure = self.structure(k)
        memo = self._evidence_memo.get(k)
        hit = None if memo is None else memo.select(self.config, structure, records, domain)
        if hit is not None:
            return hit
        obj = label_objects(domain, k, self._own, self._joiners)
        colour = self.colour_loglik(k, domain, objects=obj)
        palette = self.palette_count_loglik(k, domain, objects=obj)
        axis = {lab: i for i, lab in enumerate(domain)}
        self._evidence_memo[k] = EvidenceMemo(self.config, structure, records, axis, colour, palette)
        return colour, palette

    def _palette_records(self, domain: Sequence[Label]) -> dict[int, tuple]:
        """What the evidence of ``domain``'s labels reads of each of their objects: its own
        palette stroke and its joiner label (None where it has none), as the memos of
        :mod:`models.jorge.memo` compare them."""
        return {o: (self._own.get(o), self._joiners.get(o)) for o in frozenset().union(*domain)}

    def chain_log_ratio(self, k: int) -> np.ndarray | None:
        """Colour correction of stroke ``k`` over (parent label, label) for
        ``NetworkConfig.chain_palette``: where the parent's label and ``k``'s are one
        person alone whose palette is not their own yet (:meth:`_borrowed`), the colour
        (eq. 6) and palette-count log-likelihoods of ``k`` with the parent stroke's palette
        as the person's, minus those of :meth:`evidence_loglik` (the recorded palette);
        0 elsewhere.

        Returns
        -------
        ndarray, shape (len(parent domain), len(domain)), or None
            None where nothing is corrected (off, not one parent, no such pair). A fresh
            array, read off the node's :class:`~models.jorge.memo.ChainMemo` where it can
            be (the same numbers as computing it afresh).
        """
        node = self.nodes[k]
        if not self.config.chain_palette or len(node.parents) != 1:
            return None
        (p,) = node.parents
        dom_p, dom = self.current_domain(p), tuple(node.domain)
        records = self._palette_records(dom)
        structure = self.structure(k)
        memo = self._chain_memo.get(k)
        hit, table = (False, None) if memo is None else memo.select(self.config, structure, records, dom_p, dom)
        if hit:
            return table
        table, cells = self._new_chain_log_ratio(k, p, dom_p, dom)
        axes = ({lab: i for i, lab in enumerate(dom_p)}, {lab: j for j, lab in enumerate(dom)})
        self._chain_memo[k] = ChainMemo(self.config, structure, records, axes, table, cells)
        return table.copy() if cells.any() else None

    def _new_chain_log_ratio(self, k: int, p: int, dom_p: tuple[Label, ...],
                             dom: tuple[Label, ...]) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`chain_log_ratio` computed afresh (``p``: the parent), as a table (zeros
        where nothing is corrected) and its cells (bool), each shape (len(dom_p), len(dom))."""
        row = {lab: i for i, lab in enumerate(dom_p)}
        cells = [(row[lab], j) for j, lab in enumerate(dom)
                 if len(lab) == 1 and lab in row and self._borrowed(next(iter(lab)), k)]
        out = np.zeros((len(dom_p), len(dom)))
        mask = np.zeros(out.shape, dtype=bool)
        if not cells:
            return out, mask
        labs = [dom[j] for _, j in cells]
        # the same evidence with the parent stroke as each person's own palette (as
        # freezing it alone would make it) against the recorded palettes
        alt = label_objects(labs, k, {**self._own, **{o: p for lab in labs for o in lab}}, self._joiners)
        rec = label_objects(labs, k, self._own, self._joiners)
        diff = (self.colour_loglik(k, labs, objects=alt) + self.palette_count_loglik(k, labs, objects=alt)
                - self.colour_loglik(k, labs, objects=rec) - self.palette_count_loglik(k, labs, objects=rec))
        for (i, j), d in zip(cells, diff):
            out[i, j] = d
            mask[i, j] = True
        return out, mask

    def _borrowed(self, o: int, k: int) -> bool:
        """Whether object ``o`` (not born at ``k``) has a palette that is not its own yet:
        a member of a new group or a joiner with no stroke frozen to it alone."""
        return birth_stroke(o) != k and int(o) not in self._own and self._born_with_others(o)

    def _born_with_others(self, o: int) -> bool:
        """Whether object ``o``'s birth palette holds others' colours too: a member of a
        new group, or a joiner (:meth:`freeze`)."""
        return cohort_size(o) > 1 or int(o) in self._joiners

    def cpd_table(self, k: int) -> np.ndarray:
        """CPD table of (non-frozen) node ``k`` over its parents' current domains.

        Returns
        -------
        ndarray, shape (*parent_domain_sizes, domain_size)
            Rows sum to 1, or (``truncate_pruned``) to the mass the pruning kept. A
            fresh array, read off the node's :class:`~models.jorge.memo.TableMemo` where
            it can be (the same numbers as computing it afresh).
        """
        node = self.nodes[k]
        parent_domains = self.parent_domains(k)
        shared = self.shared(k)
        memo = self._cpd_memo.get(k)
        table = None if memo is None else memo.select(self.config, shared, parent_domains, node.domain)
        if table is None:
            table = self._new_cpd_table(k, parent_domains, shared)
            exact = not (node.parents and self.config.truncate_pruned)
            self._cpd_memo[k] = TableMemo.of(self.config, shared, parent_domains, node.domain, table, exact)
            table = table.copy()
        return table

    def _new_cpd_table(self, k: int, parent_domains: list[tuple[Label, ...]], shared: list[bool]) -> np.ndarray:
        """:meth:`cpd_table` computed afresh (:func:`~models.jorge.labels.child_table` or
        :func:`~models.jorge.labels.root_table`)."""
        node = self.nodes[k]
        self._check_table_size(k, parent_domains)
        if node.parents:
            return child_table(parent_domains, shared, node.domain,
                               frozenset({k}), self.config.labels, truncate=self.config.truncate_pruned)
        return root_table(node.domain, frozenset({k}), self.config.labels)

    def _check_table_size(self, k: int, parent_domains: list[tuple[Label, ...]]) -> None:
        """Raise a :class:`ModelError` if node ``k``'s CPD table over ``parent_domains``
        would hold more than ``_MAX_TABLE_ENTRIES`` entries."""
        entries = math.prod(len(d) for d in parent_domains) * len(self.nodes[k].domain)
        if entries > _MAX_TABLE_ENTRIES:
            raise ModelError(
                f"node {k}: its CPD table over unpruned domains would hold {entries:.3g} entries "
                f"(limit {_MAX_TABLE_ENTRIES:.0e}); new groups and joins make admissible domains "
                "grow along a chain: label on line (OnlineLabeller prunes the domains) or "
                "prune them (set_domain)"
            )

    # --- freezing and pruning --------------------------------------------------------------
    def freeze(self, k: int, label: Label) -> None:
        """Fix node ``k`` to ``label`` (seed 004, sec. 5: dead nodes keep their MAP label).

        A member of a new group frozen alone gets that stroke's palette as its own
        (:meth:`palette_stroke`; issue 16): the group's birth palette holds every member's
        colours, so without it the members of a pair that entered together stay
        exchangeable and every later split is a coin toss. A stroke frozen to a label with
        objects born there and inherited ones (a join; with new groups anywhere, also a new
        group joining) records its newcomers as joiners, whose birth palette holds the
        inherited colours too: each is known only in a label with its whole birth label
        (:func:`models.jorge.labels.label_objects`) and takes the palette of the first
        stroke frozen to it alone in the same way (issue 16, tenth round)."""
        node = self.nodes[k]
        if label not in node.domain:
            raise InputError(f"node {k}: cannot freeze to {set(label)}, not in its domain")
        node.frozen = label
        self._cpd_memo.pop(k, None)
        self._evidence_memo.pop(k, None)
        self._chain_memo.pop(k, None)
        self._replace_joiners(k, label)
        if len(label) == 1:
            (o,) = label
            if self._born_with_others(o) and k < self._own.get(int(o), k + 1):
                self._own[int(o)] = k

    def set_tentative_joiners(self, labels: Mapping[int, Label]) -> None:
        """Treat the newcomers of each unfrozen node ``k`` whose current label
        ``labels[k]`` is a join (objects born at ``k`` beside inherited ones) as joiners
        now, as :meth:`freeze` will (issue 16, fourteenth round); replaces ``k``'s earlier
        tentative joiners. Until its birth node froze, a joiner's birth palette (which
        holds the inherited people's colours too) counted as its own, and a continuation
        labelled the newcomer alone explained the whole pair's colours.

        Parameters
        ----------
        labels : mapping int -> Label
            Current labels of nodes (frozen ones are skipped).

        Raises
        ------
        InputError
            A node that does not exist, or a label outside its domain (nothing changes).
        """
        for k, label in labels.items():
            if not 0 <= k < len(self.nodes) or (self.nodes[k].frozen is None and label not in self.nodes[k].domain):
                raise InputError(f"set_tentative_joiners: node {k} has no label {set(label)} in its domain")
        for k, label in labels.items():
            if self.nodes[k].frozen is None:
                born = self._replace_joiners(k, label)
                if born:
                    self._tentative[k] = born

    def _replace_joiners(self, k: int, label: Label) -> list[int]:
        """Drop node ``k``'s tentative joiners, then record the newcomers of ``label`` as
        joiners when it is a join (objects born at ``k`` beside inherited ones); returns
        them (empty otherwise)."""
        for o in self._tentative.pop(k, ()):
            del self._joiners[o]
        born = [int(o) for o in label if birth_stroke(o) == k]
        if not born or len(born) == len(label):
            return []
        self._joiners.update(dict.fromkeys(born, label))
        return born

    @property
    def _joined(self) -> dict[int, Label]:
        """The joiners whose birth node is frozen (:meth:`freeze`), with their birth labels."""
        return {o: lab for o, lab in self._joiners.items() if self.nodes[birth_stroke(o)].frozen is not None}

    def set_domain(self, k: int, domain: Sequence[Label]) -> None:
        """Replace the (pruned) domain of an active node; its new label always stays."""
        node = self.nodes[k]
        if node.frozen is not None:
            raise InputError(f"node {k} is frozen; its domain cannot change")
        new = frozenset({k})
        dom = tuple(domain)
        if new not in dom:
            dom = (new, *dom)
        if not set(dom) <= set(node.domain):
            raise InputError(f"node {k}: a pruned domain must be a subset of the domain")
        if len(set(dom)) != len(dom):
            raise InputError(f"node {k}: repeated labels in the domain")
        node.domain = dom

    def widen(self, k: int, labels: Iterable[Label]) -> list[Label]:
        """Add admissible ``labels`` (given the parents' current domains) to the domain of
        active node ``k``, after its current labels; returns those added (in order).

        Raises
        ------
        InputError
            ``k`` is frozen.
        """
        node = self.nodes[k]
        if node.frozen is not None:
            raise InputError(f"node {k} is frozen; its domain cannot change")
        have = set(node.domain)
        wanted = [lab for lab in dict.fromkeys(frozenset(x) for x in labels) if lab not in have]
        if not wanted:
            return []
        admissible = set(self._admissible(k))
        added = [lab for lab in wanted if lab in admissible]
        node.domain = tuple(node.domain) + tuple(added)
        return added

    # --- the network of a window -----------------------------------------------------------
    def window(self, active: Sequence[int]) -> WindowNet:
        """The Bayes net of the active nodes (seed 004, eq. 11 over the active window).

        Frozen parents and frozen siblings of active nodes enter as one-state variables,
        so the active nodes' CPDs and restriction nodes see their fixed labels; all other
        frozen nodes are left out (they are constants).

        Parameters
        ----------
        active : sequence of int
            Node indices, none frozen.

        Returns
        -------
        WindowNet

        Raises
        ------
        ModelError
            An active node's CPD table would hold more than 5e7 entries (checked for
            every node before any table is built).
        """
        active = sorted(int(a) for a in active)
        act = set(active)
        for a in active:
            if not 0 <= a < len(self.nodes):
                raise UnknownVariableError(f"window: unknown node {a}")
            if self.nodes[a].frozen is not None:
                raise InputError(f"window: node {a} is frozen and cannot be active")
        for a in active:  # every table's size checked before any is built
            self._check_table_size(a, self.parent_domains(a))
        boundary: set[int] = set()
        pairs: set[tuple[int, int]] = set()
        for a in active:
            for p in self.nodes[a].parents:
                if p not in act:
                    if self.nodes[p].frozen is None:
                        raise InputError(
                            f"window: parent {p} of active node {a} is neither active nor frozen"
                        )
                    boundary.add(p)
            for s in self.siblings(a):
                pairs.add((min(a, s), max(a, s)))
                if s not in act:
                    boundary.add(s)
        # a sibling outside the window that is not frozen yet (a later node) stays out
        boundary = {b for b in boundary if self.nodes[b].frozen is not None}
        pairs = {(i, j) for i, j in pairs if (i in act or i in boundary) and (j in act or j in boundary)}
        variables, cpds = [], []
        domains: dict[str, tuple[Label, ...]] = {}
        for b in sorted(boundary):
            name = node_name(b)
            lab = self.nodes[b].frozen
            domains[name] = (lab,)
            variables.append(DiscreteVariable(name, 1, (format_label(lab),)))
            cpds.append(TabularCPD(name, [], np.ones(1)))
        soft: dict[str, np.ndarray] = {}
        kept_nodes: list = []
        for a in active:
            name = node_name(a)
            dom = self.nodes[a].domain
            domains[name] = dom
            variables.append(DiscreteVariable(name, len(dom), tuple(format_label(x) for x in dom)))
            parents = [node_name(p) for p in self.nodes[a].parents]
            table = self.cpd_table(a)
            corr = self.chain_log_ratio(a)
            if corr is not None:  # chain_palette: a factor on (parent, x_a), scaled to max 1,
                table = table * np.exp(corr - corr.max())  # row sums to m_a with the kept mass
            kept = table.sum(axis=-1)
            cpds.append(TabularCPD(name, parents, table / kept[..., None]))
            if parents and np.any(kept < 1.0 - 1e-12):
                kept_nodes.append((kept_name(a), parents, kept))
            ll = self.evidence_loglik(a)
            soft[name] = np.exp(ll - ll.max())
        evidence: dict[str, int] = {}
        # p(m_k = 1 | parents) = mass kept (truncate_pruned) times the chain factor's row sums
        for name, parents, kept in kept_nodes:
            variables.append(DiscreteVariable(name, 2, ("0", "1")))
            kept = np.minimum(kept, 1.0)  # rounding: a full row may sum to 1 + 1e-16
            cpds.append(TabularCPD(name, parents, np.stack([1.0 - kept, kept], axis=-1)))
            evidence[name] = 1
        for i, j in sorted(pairs):
            name = restriction_name(i, j)
            variables.append(DiscreteVariable(name, 2, ("0", "1")))
            cpds.append(self._restriction_cpd(name, i, j, domains))
            evidence[name] = 1
        bn = BayesNet(variables, cpds)
        return WindowNet(bn, evidence, soft, domains, tuple(active), tuple(sorted(boundary)))

    def _restriction_cpd(self, name: str, i: int, j: int, domains: dict) -> TabularCPD:
        """Restriction node of siblings ``i < j`` (eq. 5); the group of :meth:`cover_parent`,
        where there is one in the window, is its parent too
        (:func:`models.jorge.labels.restriction_table`)."""
        di, dj = domains[node_name(i)], domains[node_name(j)]
        group = self.cover_parent(i, j)
        if group is not None and node_name(group) in domains:
            p = node_name(group)
            table = restriction_table(di, dj, False, domains[p], self.config.labels.split_cover)
            return TabularCPD(name, [p, node_name(i), node_name(j)], table)
        return TabularCPD(name, [node_name(i), node_name(j)], restriction_table(di, dj, self.nested(i, j)))


@dataclass(frozen=True)
class Inference:
    """Result of exact inference on a window.

    Attributes
    ----------
    labels : dict int -> Label
        MAP label of every active node (eq. 1 / eq. 11).
    log_prob : float
        :math:`\\log P(x^*, r = 1)` times the colour likelihoods (scaled to max 1 per node).
    marginals : dict int -> ndarray (num_labels,)
        Posterior of every active node's labels.
    log_evidence : float
    """

    labels: dict
    log_prob: float
    marginals: dict
    log_evidence: float


@dataclass(frozen=True)
class WindowNet:
    """A Bayes net of one inference window and its evidence.

    Attributes
    ----------
    bn : BayesNet
    evidence : dict name -> int
        ``r = 1`` for every restriction node.
    soft_evidence : dict name -> ndarray
        Colour likelihood of every active node (scaled to max 1).
    domains : dict name -> tuple of Label
        States of every label node (one label for frozen boundary nodes).
    active, boundary : tuple of int
    """

    bn: BayesNet
    evidence: dict
    soft_evidence: dict
    domains: dict
    active: tuple
    boundary: tuple

    def with_colour_nodes(self) -> tuple[BayesNet, dict]:
        """The same model with the soft evidence (colours, and size where recorded) as
        explicit binary children ``y{k}``
        observed 1, ``p(y = 1 | x) = lambda(x)`` (virtual evidence as a node), for engines
        without soft evidence (pgmpy). Its joint with the evidence equals ours exactly.

        Returns
        -------
        bn : BayesNet
        evidence : dict name -> int
        """
        variables = list(self.bn.variables.values())
        cpds = list(self.bn.cpds.values())
        evidence = dict(self.evidence)
        for name, lik in self.soft_evidence.items():
            k = int(name[1:])
            y = colour_name(k)
            variables.append(DiscreteVariable(y, 2, ("0", "1")))
            cpds.append(TabularCPD(y, [name], np.stack([1.0 - lik, lik], axis=-1)))
            evidence[y] = 1
        return BayesNet(variables, cpds), evidence


def solve(win: WindowNet, marginals: bool = True) -> Inference:
    """MAP labelling and marginals of a window with :mod:`inference.exact`.

    Parameters
    ----------
    win : WindowNet
    marginals : bool
        Also calibrate a junction tree for every active node's posterior.

    Returns
    -------
    Inference
    """
    assignment, log_prob = map_assignment(win.bn, win.evidence, win.soft_evidence)
    labels = {k: win.domains[node_name(k)][assignment[node_name(k)]] for k in win.active}
    marg: dict[int, np.ndarray] = {}
    log_ev = float("nan")
    if marginals:
        cal = JunctionTree(win.bn).calibrate(win.evidence, win.soft_evidence)
        marg = {k: cal.marginals[node_name(k)] for k in win.active}
        log_ev = cal.log_evidence
    return Inference(labels, log_prob, marg, log_ev)


def _linear_quantile(values: np.ndarray, q: float) -> float:
    """``np.quantile(values, q)`` (linear interpolation, Hyndman and Fan's definition 7)
    for a short 1-D array with no NaN, in about a twentieth of its time: the same value, bit for
    bit on numpy 2 (``tests/models/jorge/test_jorge_memo.py``).

    Parameters
    ----------
    values : ndarray, shape (n,), n >= 1
    q : float in [0, 1]
    """
    v = np.sort(values)
    at = (v.size - 1) * q
    if at >= v.size - 1:
        return float(v[-1])
    lo = int(math.floor(at))
    t = at - lo
    a, b = float(v[lo]), float(v[lo + 1])
    return b - (b - a) * (1 - t) if t >= 0.5 else a + (b - a) * t


# pixel coordinates / sizes beyond this are not an image (a unit or scale mistake)
_MAX_PIXELS = 1e6
_MAX_TABLE_ENTRIES = 5e7  # a CPD table of one node (400 MB of float64)


def _check_palette(k: int, palette, pool_size: int) -> None:
    """A stroke's palette: 1-D integer colour ids in ``0..pool_size-1`` (no wrap of -1)."""
    pal = np.asarray(palette)
    if pal.ndim != 1 or not np.issubdtype(pal.dtype, np.integer):
        raise InputError(f"stroke {k}: palette must be 1-D integer colour ids, got {palette!r}")
    if np.any(pal < 0) or np.any(pal >= pool_size):
        raise InputError(f"stroke {k}: palette ids must be in 0..{pool_size - 1}, got {pal.tolist()}")


def _check_frames(k: int, stroke: Stroke, num_points: int) -> None:
    """A stroke's frames: ``num_points`` increasing integers from ``start`` to ``end``."""
    fr = np.asarray(stroke.frames)
    if fr.shape != (num_points,) or not np.issubdtype(fr.dtype, np.integer):
        raise InputError(
            f"stroke {k}: frames must be {num_points} integers (one per position), "
            f"got shape {fr.shape} dtype {fr.dtype}"
        )
    if fr[0] != stroke.start or fr[-1] != stroke.end or np.any(np.diff(fr) <= 0):
        raise TimeOrderError(
            f"stroke {k}: frames must increase from start {stroke.start} to end {stroke.end}"
        )

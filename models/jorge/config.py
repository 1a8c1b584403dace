r"""Settings of the label network (:class:`NetworkConfig`) and the parameters fitted for it
on the declared training split (:mod:`models.jorge.fit`): the label CPD parameters
(:data:`FITTED_LABELS`), the palette evidence tables (:data:`FITTED_PALETTE_COUNTS`,
:data:`FITTED_PALETTE_GAINS`) and the split-cover prior (:data:`FITTED_SPLIT_COVER`).

:mod:`models.jorge.network` builds and solves the network these settings describe, and
re-exports every name here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from dbn.checks import check_number_fields, refuse_complex
from dbn.errors import ModelError
from models.jorge.evidence import gain_bins_rise
from models.jorge.labels import LabelParams

__all__ = [
    "NetworkConfig",
    "FITTED_LABELS",
    "FITTED_PALETTE_COUNTS",
    "FITTED_PALETTE_GAINS",
    "FITTED_PALETTE_MISSING",
    "FITTED_SPLIT_COVER",
]


FITTED_SPLIT_COVER = (1.0, 1.0, 0.68, 0.9871794871794872, 0.94)
""":math:`p_n` for ``LabelParams.split_cover`` (issue 16's sixteenth round; in the default
network, :data:`FITTED_LABELS`, since the twenty-second), the probability that the two children
of a group of ``n`` people that take disjoint parts of it hold all of its people, fitted by
:func:`models.jorge.fit.fit_split_cover` on the declared training split (the rule's links,
seeds 100-109; groups of 3: 16 of 23 splits, of 4: 76 of 76, of 5: 46 of 48, add-one smoothed).
Seed 004's pieces are drawn independently and eq. 5 only forbids overlap, so its prior gives a
partition 6 / 12, 14 / 50 and 30 / 180 of the disjoint pairs of a group of 3 / 4 / 5
(:func:`models.jorge.labels.split_loss_weights`). Turn it off, for seed 004's eq. 5 alone, with
``NetworkConfig(labels=replace(FITTED_LABELS, split_cover=()))``. The window inference uses it,
and since issue 16's seventeenth round the instant (eq. 12) labels too
(:meth:`models.jorge.online.OnlineLabeller.instant_posterior`, given the group's current
label). Refitting the default network on the training split
(:func:`models.jorge.fit.fit_parameters`, seeds 100-109) gives these numbers again.

Four comparisons, each declared before it ran. On the search's scoring sets (the training
sequences and SIMULATED meetings) with seeds 100-104 and fresh seeds 245-264 and 265-304, 65
sets, the combined error fell from 0.1958 to 0.1930, paired -0.0028 with standard error 0.0014
(-1.97 SE; lower on 35 of 65 sets); meetings 0.093 -> 0.087, their strokes of 3+ people for k =
3 / 4 / 5 0.149 / 0.299 / 0.393 -> 0.152 / 0.253 / 0.383, the real training sequences 0.2472 ->
0.2463. The rule declared before that second, larger comparison asked for -2 SE, so it did not
land (:data:`models.jorge.fit.CONFIRM_SEEDS` records every comparison). A third look, with the
instant labels using it too, on 40 fresh seeds (305-344) alone: 0.1973 -> 0.1948, paired
-0.0026 (standard error 0.0020), lower on 18 of 40; meetings of k = 3 / 4 / 5 0.065 / 0.093 /
0.140 -> 0.069 / 0.076 / 0.126, the PETS2009 S1 crowds 0.601 / 0.795 -> 0.603 / 0.797; not
landed (the rule asked for -2 SE). The fourth look (issue 16's twenty-second round, after a
training-side SIMULATED meeting of four lost its group when a window let one half of a 2 + 2
split drop a member and take an unseen joiner) asked for below -1 standard error on 40 fresh
seeds (425-464) and below -2 for the three independent looks combined (inverse variance), with
no acceptance bar of the quick benchmark flipping: 0.1885 -> 0.1859, paired -0.0025 (standard
error 0.0016, -1.6 SE), lower on 26 of 40 (higher on 12); combined -0.0027 (standard error
0.0009, -2.9 SE). Meetings of k = 3 / 4 / 5 0.0499 / 0.0863 / 0.1098 -> 0.0427 / 0.0658 /
0.1058, their strokes of 3+ people 0.108 / 0.259 / 0.331 -> 0.114 / 0.179 / 0.302; the PETS2009
S1 crowds 0.5845 / 0.7968 -> 0.5866 / 0.8037; the CAVIAR training sequences unchanged. Landed:
the default since then. It helps groups of four and five most and costs the PETS2009 S1 crowds
a little."""


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
    split_cover=FITTED_SPLIT_COVER,
    split_normalise=True,
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
Ninth round (issue 16): the re-identification pass (:func:`models.jorge.reid.reidentify`)
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
(:func:`models.jorge.reid.reidentify`) examined the objects in id order, which puts a
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
on 2 cores) and checks the fitted numbers.
Twenty-second round: ``split_cover`` is :data:`FITTED_SPLIT_COVER` (above: fitted on the
same split, landed on fresh seeds 425-464). Twenty-third round: ``split_normalise`` is on
(nothing fitted: the split's restriction divides by :func:`models.jorge.labels.split_pair_scale`
of the group's size; landed on its second look, fresh seeds 545-584, combined with the first,
505-544, under a rule declared before each ran: :data:`models.jorge.fit.CONFIRM_SEEDS`)."""


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


FITTED_PALETTE_MISSING = (
    (
        (-2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367),
        (-0.005780362915499425, -7.641084249174914, -7.641084249174914, -7.641084249174914, -7.641084249174914, -7.641084249174914, -7.641084249174914, -7.641084249174914, -7.641084249174914, -7.641084249174914, -7.641084249174914, -7.641084249174914, -7.641084249174914),
        (-0.07898841131863032, -5.062595033026967, -5.062595033026967, -5.062595033026967, -5.062595033026967, -5.062595033026967, -5.062595033026967, -5.062595033026967, -5.062595033026967, -5.062595033026967, -5.062595033026967, -5.062595033026967, -5.062595033026967),
        (-0.060624621816434854, -4.442651256490317, -5.8289456176102075, -4.219507705176107, -5.135798437050262, -5.8289456176102075, -5.8289456176102075, -5.8289456176102075, -5.8289456176102075, -5.8289456176102075, -5.8289456176102075, -5.8289456176102075, -5.8289456176102075),
        (-0.21551962620355042, -3.891820298110627, -3.0808900818942977, -4.584967478670572, -3.891820298110627, -5.278114659230518, -5.278114659230518, -2.793208009442517, -5.278114659230518, -5.278114659230518, -5.278114659230518, -5.278114659230518, -5.278114659230518),
    ),
    (
        (-0.013937507843781624, -6.7650389767805414, -6.7650389767805414, -6.7650389767805414, -6.7650389767805414, -6.7650389767805414, -6.7650389767805414, -6.7650389767805414, -6.7650389767805414, -6.7650389767805414, -6.7650389767805414, -6.7650389767805414, -6.7650389767805414),
        (-0.050858417233490966, -5.488937726156687, -5.488937726156687, -5.488937726156687, -5.488937726156687, -5.488937726156687, -5.488937726156687, -5.488937726156687, -5.488937726156687, -5.488937726156687, -5.488937726156687, -5.488937726156687, -5.488937726156687),
        (-0.3101549283038396, -3.8066624897703196, -3.8066624897703196, -3.8066624897703196, -3.8066624897703196, -3.8066624897703196, -3.8066624897703196, -3.8066624897703196, -3.8066624897703196, -3.8066624897703196, -3.8066624897703196, -3.8066624897703196, -3.8066624897703196),
        (-0.146092618497496, -3.536116699561526, -4.634728988229636, -4.634728988229636, -4.634728988229636, -4.634728988229636, -4.634728988229636, -4.634728988229636, -4.634728988229636, -4.634728988229636, -4.634728988229636, -4.634728988229636, -4.634728988229636),
        (-0.14629209321473707, -4.0312864262549635, -5.1298987149230735, -4.436751534363128, -3.520460802488973, -4.0312864262549635, -4.436751534363128, -4.436751534363128, -5.1298987149230735, -5.1298987149230735, -5.1298987149230735, -5.1298987149230735, -5.1298987149230735),
    ),
    (
        (-0.03692727259221836, -5.802118375377063, -5.802118375377063, -5.802118375377063, -5.802118375377063, -5.802118375377063, -5.802118375377063, -5.802118375377063, -5.802118375377063, -5.802118375377063, -5.802118375377063, -5.802118375377063, -5.802118375377063),
        (-0.3184537311185346, -3.784189633918261, -3.784189633918261, -3.784189633918261, -3.784189633918261, -3.784189633918261, -3.784189633918261, -3.784189633918261, -3.784189633918261, -3.784189633918261, -3.784189633918261, -3.784189633918261, -3.784189633918261),
        (-0.7375989431307791, -3.1354942159291497, -3.1354942159291497, -3.1354942159291497, -3.1354942159291497, -3.1354942159291497, -3.1354942159291497, -3.1354942159291497, -3.1354942159291497, -3.1354942159291497, -3.1354942159291497, -3.1354942159291497, -3.1354942159291497),
        (-0.2696635669491026, -3.3141860046725258, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471, -4.007333185232471),
        (-0.1823215567939546, -3.6635616461296463, -4.356708826689592, -4.356708826689592, -4.356708826689592, -4.356708826689592, -4.356708826689592, -4.356708826689592, -4.356708826689592, -4.356708826689592, -4.356708826689592, -4.356708826689592, -4.356708826689592),
    ),
    (
        (-0.07275935428242832, -5.14166355650266, -5.14166355650266, -5.14166355650266, -5.14166355650266, -5.14166355650266, -5.14166355650266, -5.14166355650266, -5.14166355650266, -5.14166355650266, -5.14166355650266, -5.14166355650266, -5.14166355650266),
        (-0.3272129112084162, -3.7612001156935624, -3.7612001156935624, -3.7612001156935624, -3.7612001156935624, -3.7612001156935624, -3.7612001156935624, -3.7612001156935624, -3.7612001156935624, -3.7612001156935624, -3.7612001156935624, -3.7612001156935624, -3.7612001156935624),
        (-0.916290731874155, -2.995732273553991, -2.995732273553991, -2.995732273553991, -2.995732273553991, -2.995732273553991, -2.995732273553991, -2.995732273553991, -2.995732273553991, -2.995732273553991, -2.995732273553991, -2.995732273553991, -2.995732273553991),
        (-0.40546510810816444, -3.58351893845611, -3.58351893845611, -3.58351893845611, -3.58351893845611, -3.58351893845611, -3.58351893845611, -3.58351893845611, -3.58351893845611, -3.58351893845611, -3.58351893845611, -3.58351893845611, -3.58351893845611),
        (-0.6359887667199967, -2.1400661634962708, -3.5263605246161616, -2.833213344056216, -3.5263605246161616, -3.5263605246161616, -3.5263605246161616, -3.5263605246161616, -3.5263605246161616, -3.5263605246161616, -3.5263605246161616, -3.5263605246161616, -3.5263605246161616),
    ),
    (
        (-0.1823215567939546, -4.276666119016055, -4.276666119016055, -4.276666119016055, -4.276666119016055, -4.276666119016055, -4.276666119016055, -4.276666119016055, -4.276666119016055, -4.276666119016055, -4.276666119016055, -4.276666119016055, -4.276666119016055),
        (-0.3794896217049037, -3.6375861597263857, -3.6375861597263857, -3.6375861597263857, -3.6375861597263857, -3.6375861597263857, -3.6375861597263857, -3.6375861597263857, -3.6375861597263857, -3.6375861597263857, -3.6375861597263857, -3.6375861597263857, -3.6375861597263857),
        (-2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367),
        (-0.9985288301111273, -2.9444389791664407, -2.9444389791664407, -2.9444389791664407, -2.9444389791664407, -2.9444389791664407, -2.9444389791664407, -2.9444389791664407, -2.9444389791664407, -2.9444389791664407, -2.9444389791664407, -2.9444389791664407, -2.9444389791664407),
        (-0.32378707709389715, -3.1570004211501135, -3.8501476017100584, -3.8501476017100584, -3.8501476017100584, -3.8501476017100584, -3.8501476017100584, -3.8501476017100584, -3.8501476017100584, -3.8501476017100584, -3.8501476017100584, -3.8501476017100584, -3.8501476017100584),
    ),
    (
        (-0.09381875521765486, -4.897839799950911, -4.897839799950911, -4.897839799950911, -4.897839799950911, -4.897839799950911, -4.897839799950911, -4.897839799950911, -4.897839799950911, -4.897839799950911, -4.897839799950911, -4.897839799950911, -4.897839799950911),
        (-0.3462762367178338, -3.713572066704308, -3.713572066704308, -3.713572066704308, -3.713572066704308, -3.713572066704308, -3.713572066704308, -3.713572066704308, -3.713572066704308, -3.713572066704308, -3.713572066704308, -3.713572066704308, -3.713572066704308),
        (-2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367, -2.5649493574615367),
        (-1.6094379124341003, -2.70805020110221, -2.70805020110221, -2.70805020110221, -2.70805020110221, -2.70805020110221, -2.70805020110221, -2.70805020110221, -2.70805020110221, -2.70805020110221, -2.70805020110221, -2.70805020110221, -2.70805020110221),
        (-0.16598513747426116, -3.7495040759303713, -4.442651256490317, -4.442651256490317, -4.442651256490317, -4.442651256490317, -4.442651256490317, -4.442651256490317, -4.442651256490317, -4.442651256490317, -4.442651256490317, -4.442651256490317, -4.442651256490317),
    ),
)
""":math:`\\log p(d \\mid m, b(u))` for ``NetworkConfig.palette_missing_table`` (issue 16,
thirty-fourth round; :func:`models.jorge.evidence.palette_missing_log_likelihood`): the known
colours :math:`d = 0..12` a stroke's palette lacks, per newcomers :math:`m = 0..5` and bin of
the known colours :math:`u` (``palette_gain_bins``), fitted by
:func:`models.jorge.fit.fit_parameters` on the declared training split (the rule's links,
seeds 100-109): the true labels lack none in 5082 of 5137 strokes, so a label that swaps a
member for someone else, whose gain :math:`e` is that of the true label, now pays for the
colours it expects and the palette lacks. Chosen by a comparison declared before it ran
(:data:`models.jorge.fit.CONFIRM_SEEDS`, ``python -m models.jorge.confirm --set
palette_missing=true --seeds 880 920``): over the 12 sets of each of seeds 880-919,
0.2068 -> 0.1941, paired difference -0.0127 (one standard error 0.0015), lower on 37 of 40
seeds (diagnosis before declaring, seeds 100-104: -0.0073, SE 0.0053); no bar of the quick
benchmark flipped, and the full run's held-out validation was 0.0280."""


_TABLES = ("palette_count_table", "palette_gain_table", "palette_missing_table",
           "palette_gain_bins")
"""The :class:`NetworkConfig` fields that hold tables: kept as nested tuples (an array given
is converted, so configs compare and print as the defaults do)."""


def _nested_tuple(value: Any) -> Any:
    """An array (numpy, jax) or nested lists as nested tuples; anything else as it is."""
    if hasattr(value, "tolist") and not isinstance(value, str):
        value = value.tolist()
    if isinstance(value, list | tuple):
        return tuple(_nested_tuple(v) for v in value)
    return value


def _as_table(name: str, value) -> np.ndarray:
    """A palette table as a float array; a ragged or non-numeric one as an empty array, which
    every shape check of :class:`NetworkConfig` refuses, naming the field; complex numbers
    are refused naming it."""
    refuse_complex(f"NetworkConfig.{name}", value, ModelError)
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        return np.zeros(0)


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
        ``max_gap_frames`` 30 and ``sibling_window`` 20 (issue 4) were scored again on
        the search's scoring sets, seeds 100-109 (issue 16, twenty-fifth round): the
        combined error is flat around them (``sibling_window`` 10 / 15 / 30: +0.0032 /
        -0.0009 / +0.0026, standard errors 0.0034 / 0.0019 / 0.0020; ``max_gap_frames``
        20 / 45: +0.0002 / +0.0010, 0.0015 / 0.0024), so they stay. Thirty-first round:
        the stroke builder hides people for 5-15 frames, up to 2.1 s at PETS2009's 7 fps,
        and 1.2 s misses most of those gaps there; with SIMULATED meetings at 7 fps added to
        the scoring sets (:func:`models.jorge.fit.meeting_strokes` with ``fps``), the
        search's procedure (30 / 45 / 60 x 20 / 30, each point refitted) chose
        ``max_gap_frames`` 60, and it passed its declared confirmation on fresh seeds
        720-759 (:data:`models.jorge.fit.CONFIRM_SEEDS`: 7-fps meetings 0.269 -> 0.176,
        the 25-fps sets unchanged). Not landed: in the full benchmark the held-out
        PETS2009 S2L1 got worse (0.103 -> 0.139 over stroke seeds 0-4, worse on four of
        the five, though its links were right more often, 0.58 -> 0.80), the slowest
        sequence fell to 20.7x real time (the bar is 20) and the largest clique table grew
        from 87,120 to 190,080 entries. Vetoing it looked at the held-out sequence, so
        the validation figure is no longer blind to this choice. A fallback instead (a stroke
        the rule leaves without a parent may continue the nearest stroke without a child
        within 60 frames) passed its confirmation too (fresh seeds 760-799: 7-fps meetings
        0.275 -> 0.220, the 25-fps sets unchanged) and was not landed either: the quick
        run's slowest sequence ran at 0.76-0.93x the default's speed and the held-out
        validation rose (0.074 -> 0.080). Thirty-second round: the same fallback for groups
        alone (both regions group-sized by the size evidence; single people left to the
        re-identification pass, which recovers most of them, while nothing recovers a
        group's label) passed its confirmation (fresh seeds 800-839: 7-fps meetings 0.280 ->
        0.232, the 25-fps sets unchanged) and kept the quick run's speed, but the full run's
        held-out validation rose 0.0737 -> 0.0999 (PETS2009 S2L1 0.103 -> 0.140): not
        landed. Three long-gap rules now agree that the real 7-fps sequence loses by them.
    labels : LabelParams
        :math:`P_{new}, P_{merge}, P_{split}` and the maximum group size.
    colour_mode : {"hyper", "ratio", "eq6"}
        Colour model (see :func:`models.jorge.evidence.colour_log_likelihood`); default
        ``"hyper"``: the likelihood ratio against chance matches of distinct colours.
    match_prob : float
        :math:`P` of eq. 6.
    pool_size : int
        Number of colours in the pool.
    size_evidence : bool
        Also use the stroke's region size as soft evidence on the number of people of
        its label (:func:`models.jorge.evidence.size_log_likelihood`; our addition, not in
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
        that many or more) (:func:`models.jorge.evidence.palette_count_log_likelihood`; our addition, issue 16);
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
        16): where both regions have boxes, the new stroke's first box must meet the
        earlier stroke's last box grown by ``v_box`` * gap_s region sizes on every side
        (``LabelGraph._boxes_near``), in place of the centre distance; elsewhere the
        scaled gate. So ``radius_scaled`` and ``v_max_scaled`` act only where a region
        has no box: 0.8 / 1.6 and 0.7 / 1.5 gave the same error on every scoring set of
        the search, seeds 100-109 (issue 16, twenty-fifth round). In crowds the box gate
        keeps split parts and merges and drops the neighbours the centre distance let in (true
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
        (:func:`models.jorge.evidence.palette_gain_log_likelihood`; issue 16). Added to the
        ``palette_count_table`` evidence when both are set; fitted by
        :func:`models.jorge.fit.fit_parameters`; default :data:`FITTED_PALETTE_GAINS`;
        ``()``: none.
    palette_missing : bool
        Whether :func:`models.jorge.fit.fit_parameters` fits ``palette_missing_table``
        (a setting: the fit leaves the table empty without it).
    palette_missing_table : tuple of tuple of tuple of float
        :math:`\\log p(d \\mid m, b(u))` of the colours :math:`d` of a label's known objects'
        palettes that the stroke's palette lacks, shape ``(max_m + 1,
        len(palette_gain_bins), pool_size + 1)``
        (:func:`models.jorge.evidence.palette_missing_log_likelihood`; issue 16,
        thirty-fourth round, our addition): the gain table sees only :math:`e = |P \\setminus
        U| - d`, blind to a member swapped for someone else. Weighted as the palette counts
        (``palette_continued``); fitted by :func:`models.jorge.fit.fit_parameters` where
        ``palette_missing`` is set; default :data:`FITTED_PALETTE_MISSING`; ``()``: none
        (before the thirty-fourth round). It reads a stroke's palette as a clean estimate
        of its people's colours, as :func:`models.jorge.strokes.build_strokes` simulates
        it; strokes whose palette is only their observed colours (``make_stroke``'s
        default) need it off, or a table refitted on such strokes.
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
    palette_missing: bool = True
    palette_missing_table: tuple = FITTED_PALETTE_MISSING
    size_once: bool = True
    truncate_pruned: bool = True
    merge_area: float = 1.0
    palette_continued: float = 0.75
    chain_palette: bool = True
    nested_links: float = 2.0
    merge_cover: float = 0.2

    def __post_init__(self) -> None:
        for name in _TABLES:  # an array's truth value raised numpy's "ambiguous" error
            object.__setattr__(self, name, _nested_tuple(getattr(self, name)))
        check_number_fields(self, ModelError)
        for name, low in (("pool_size", 1), ("sibling_window", 0), ("size_min_reference", 0),
                          ("size_reference_neighbours", 0)):  # fmt: skip
            if getattr(self, name) < low:
                raise ModelError(f"NetworkConfig.{name} must be >= {low}, "
                                 f"got {getattr(self, name)}")  # fmt: skip
        if not 0.0 <= self.size_reference_quantile <= 1.0 or not self.nested_links >= 0:
            raise ModelError(f"NetworkConfig: size_reference_quantile must be in [0, 1] and "
                             f"nested_links >= 0, got {self.size_reference_quantile} / "
                             f"{self.nested_links}")  # fmt: skip
        self._check_links()
        self._check_palette()
        self._check_size_and_colour()

    def _check_links(self) -> None:
        """The link rule's and the merge test's settings; :class:`ModelError` names the field."""
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
        if not (self.merge_area >= 0 and np.isfinite(self.merge_area)):
            raise ModelError(f"NetworkConfig.merge_area must be finite and >= 0, got {self.merge_area}")
        if not 0 <= self.merge_cover <= 1:
            raise ModelError(f"NetworkConfig.merge_cover must be in [0, 1], got {self.merge_cover}")
        if not self.radius_scaled >= 0 or not self.v_max_scaled > 0:
            raise ModelError(
                f"NetworkConfig: radius_scaled must be >= 0 and v_max_scaled > 0, got "
                f"{self.radius_scaled} / {self.v_max_scaled}"
            )

    def _check_palette(self) -> None:
        """The palette evidence's settings and tables (shapes, log probabilities)."""
        if not 0.0 <= self.palette_continued <= 1.0:
            raise ModelError(f"NetworkConfig.palette_continued must be in [0, 1], got {self.palette_continued}")
        if self.palette_count_table:
            t = _as_table("palette_count_table", self.palette_count_table)
            if t.ndim != 2 or t.shape[1] < 2 or not np.all(t <= 0):
                raise ModelError(
                    f"NetworkConfig.palette_count_table must be a 2-D table of log "
                    f"probabilities (max_k, max_count + 1), got shape {t.shape}"
                )
        bins = np.asarray(self.palette_gain_bins)
        if not gain_bins_rise(bins):
            raise ModelError(f"NetworkConfig.palette_gain_bins must rise from 0, got {self.palette_gain_bins}")
        if self.palette_gain_table:
            t = _as_table("palette_gain_table", self.palette_gain_table)
            if t.ndim not in (2, 3) or t.shape[-1] % 2 != 1 or not np.all(t <= 0) or (
                    t.ndim == 3 and t.shape[1] != bins.size):
                raise ModelError(
                    f"NetworkConfig.palette_gain_table must be a table of log probabilities "
                    f"(max_new + 1, [{bins.size} bins of palette_gain_bins,] 2 * pool_size + 1), "
                    f"got shape {t.shape}"
                )
        if not isinstance(self.palette_missing, bool):
            raise ModelError(f"NetworkConfig.palette_missing must be a bool, got {self.palette_missing!r}")
        if self.palette_missing_table:
            t = _as_table("palette_missing_table", self.palette_missing_table)
            if t.ndim != 3 or t.shape[1] != bins.size or t.shape[2] < 2 or not np.all(t <= 0):
                raise ModelError(
                    f"NetworkConfig.palette_missing_table must be a table of log probabilities "
                    f"(max_new + 1, {bins.size} bins of palette_gain_bins, pool_size + 1), got shape {t.shape}"
                )

    def _check_size_and_colour(self) -> None:
        """The colour mode, the match probability and the size evidence's parameters."""
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

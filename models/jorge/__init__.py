"""Jorge, Marques & Abrantes (seed 004): labelling strokes of pedestrians and their groups
with a Bayes net built on the fly (restriction nodes, merge/split labels, on-line mode).

Modules: :mod:`strokes` (ground-truth loaders and the simulated low-level tracker),
:mod:`labels` (admissible label sets and the CPDs of the basic structures),
:mod:`evidence` (the colour model, eq. 6, and the size and palette evidence of a label),
:mod:`config` (the network's settings and the parameters fitted on the training split),
:mod:`network` (the growing graph of strokes, links and label domains), :mod:`links`
(the link rule), :mod:`window` (the Bayes net of an inference window and its exact MAP /
marginals), :mod:`online` (periodic inference with bounded memory, eq. 12 labelling),
:mod:`reid` (the final re-identification pass), :mod:`scoring` (label errors, the true
stroke graph and the colour-only baseline), :mod:`recall` (where a stroke's right label was
lost: not admissible, pruned from its domain, or not chosen),
:mod:`memo` (what a node remembers of its CPD and evidence between inferences),
:mod:`api` (the labeller under the tracker protocol), :mod:`checkpoint` (the labeller saved
and resumed), :mod:`fit` (the parameters learned
on the declared training split), :mod:`fit_prior` (a fit on little data shrunk towards a
prior network), :mod:`confirm` (a change compared on fresh seeds),
:mod:`estimate` (the error on many SIMULATED meeting scenes, with standard errors),
:mod:`simulate` (a synthetic sequence when the real ground truth is absent),
:mod:`meeting` (SIMULATED meetings of 3-5 people), :mod:`demo` (``dbntrack demo``'s part),
:mod:`eth` (tracks in world metres, ETH / UCY ``obsmat``, through a SIMULATED camera),
:mod:`recordings` (whether a ground truth is, by its boxes, a cut or a copy of another
recording, whatever its frame numbers and ids).
"""

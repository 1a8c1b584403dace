"""The declarative layer: what a model is (variables, CPDs, Bayes nets, two-slice DBNs).

``dbn`` imports neither ``inference`` nor ``models``.
"""

"""Queries between two shapes: one module per pair of kinds, the tables between them, Hausdorff.

:mod:`.fast`
    The routes of single pairs, resolved once per pair of shape types and method: one
    (rounded) segment or triangle against another, a mesh against a (posed) mesh.
:mod:`.queries`
    The general path of the pair queries (``closest_points``, ``distance``,
    ``signed_distance``): the sides taken apart (posed, rounded, batched), the kinds looked up
    once in :mod:`.table`, then one of the answers below.
:mod:`.table`
    The pairs of primitive kinds, and the kernel module that answers each.
:mod:`.segment_segment`, :mod:`.segment_triangle`, :mod:`.triangle_triangle`
    The pair kernels, each built from the smaller queries.
:mod:`.kernels`
    The pair batch pipeline, the one-pair fast path and the rows of collections.
:mod:`.descent`, :mod:`.node_bounds`
    The simultaneous descent of two hierarchies, and the bounds that prune it.
:mod:`.composite`
    A mesh or a scene on either side: the descent's sides, and its certified finish.
:mod:`.instances`
    Scenes of posed instances, answered part by part.
:mod:`.hausdorff`
    Certified bounds on the Hausdorff distance of two meshes.

It may import :mod:`proximity.shapes` and everything below it; nothing below imports it.
"""

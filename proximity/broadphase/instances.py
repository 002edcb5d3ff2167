"""Instances: many posed copies of a few collections, searched without a tree of their primitives.

A scene of posed views of meshes (or scenes) keeps one hierarchy per
distinct collection, its *prototype*, and per instance only its pose, its
box in the world and where its primitives are numbered.  A new frame (new
poses) costs O(instances): the boxes of the prototypes' roots, moved.

A query bounds each instance's distance from below by the larger of the
distances to its world box and to its bounding sphere (the sphere of the
prototype about its root box's centre, :meth:`.tree.Tree.sphere`, through
the farthest of a mesh's vertices or of the corners of its leaves' boxes:
unlike the box, it does not grow when the instance turns).
It then visits the instances nearest first by that bound, moves the point
into each one's frame (``R^T (P - t)``, summed as
:func:`proximity.numerics.rigid.to_local` sums it) and runs the prototype's search
there (:func:`.traverse._descend`), with the best answer so far as its
cutoff, until the nearest bound left exceeds the best answer.  Distances
are the same in every frame (the poses are rigid, within
:data:`proximity.numerics.rigid.RIGID_TOLERANCE`), so the best over the instances is
the answer; ties go to the lowest index, the instances numbering their
primitives one after the other.

Each block of points (consecutive in space) first keeps only the instances
that can hold the nearest primitive of some point of the block: those whose
lower bound over the block's box is at most the block's upper bound, the
least over the instances of the farthest reach of their spheres from the
block's box (every primitive lies in its instance's sphere).  The points
then choose among those few.

The bounds are lowered by a slack before they are compared: ``2^-40``
(:data:`BOX_SLACK`), far above the rounding of the moved boxes and
spheres, plus four times the instance's ``max |R^T R - I|``, which covers
the distance in the instance's frame differing from the distance in the
world where the rotation is not exactly orthonormal; both relative to the
coordinates' magnitude.
"""

import collections
import functools
import math
import weakref

import numpy as np
from numba.core import types

from .. import primitives
from ..primitives import LANES
from ..runtime.jit import launcher, part, specialize
from ..runtime.loops import PAIR_ROWS
from ._alloc import indices, readonly
from .bounds import CULL_COLUMNS
from .traverse import (
    _C1I,
    _C2F,
    _INDEXED_TREE,
    _OUTPUTS,
    _SENTINEL,
    _TREE,
    BLOCK,
    NONE,
    SEARCH_GRAIN,
    Outputs,
    TreeArrays,
    descent,
    new_outputs,
    no_answer,
    reads_cull,
)

#: The poses and places of the instances: the prototype of each, its rotation
#: and translation, its world box (low and high corners, and the magnitude of
#: its coordinates, world and local), its bounding sphere in the world (centre
#: and radius), its relative slack, and the index of its first primitive in
#: the scene.
InstanceArrays = collections.namedtuple(
    "InstanceArrays", "prototype rotation translation box sphere slack offset"
)
_INSTANCES = types.NamedTuple(
    [
        types.Array(types.int64, 1, "C", readonly=True),
        types.Array(types.float64, 3, "C", readonly=True),
        _C2F,
        _C2F,
        _C2F,
        types.Array(types.float64, 1, "C", readonly=True),
        types.Array(types.int64, 1, "C", readonly=True),
    ],
    InstanceArrays,
)


def _signatures(tree):
    """The block's and the loop's signatures for forests of type ``tree``."""
    # (block, forest, roots, magnitudes, depth, instances, points, order, outputs, full, cutoff)
    block = types.void(
        types.int64, tree, _C1I, types.Array(types.float64, 1, "C", readonly=True), types.int64,
        _INSTANCES, _C2F, _C1I, _OUTPUTS, types.boolean, types.float64,
    )  # fmt: skip
    # (handle, first block, end block, forest, ...)
    return block, types.void(types.int64, types.int64, types.int64, *block.args[1:])


#: A forest of one tree of faces read through their vertices has the indexed signatures.
_SIGNATURES = {False: _signatures(_TREE), True: _signatures(_INDEXED_TREE)}

#: The slack on an instance's world box, relative to the coordinates' magnitude.
BOX_SLACK = 2.0**-40

DESCEND = CALL = None
SEED_POINT = True
EXACT_FALLBACK = False


def _instances_block(block, forest, roots, magnitudes, depth, inst, points, order, out, full, cutoff):
    """The nearest primitive of any instance to each point of ``block``
    (see the module docstring); outputs as :func:`.traverse._search_block`'s."""
    dist, sqr, point, feature, extra, flag, prim, undecided = out
    n = points.shape[0]
    m = inst.prototype.shape[0]
    sentinel = _SENTINEL
    stack_node = np.empty(depth + 1, np.int64)
    stack_sqr = np.empty(depth + 1)
    lanes = np.empty(LANES, np.int64)
    z = np.empty((PAIR_ROWS, LANES))
    lower = np.empty(m)
    visit = np.empty(m, np.int64)
    pick = np.empty(m, np.int64)
    near = _block_instances(block, inst, points, order, cutoff)
    # The previous point's closest point, in the world: its distance bounds
    # the next point's answer (points come in spatial order), as in
    # :func:`.traverse._search_block`.
    near_x, near_y, near_z = math.nan, math.nan, math.nan
    for j in range(block * BLOCK, min(n, (block + 1) * BLOCK)):
        i = order[j]
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        best, best_index, best_k, upper, lowest = math.inf, sentinel, -1, math.inf, math.inf
        w_sqr, w_x, w_y, w_z, w_a0, w_a1, w_a2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        w_feature = NONE
        w_flag = False
        winner = -1
        finite = math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)
        if finite:
            size = max(max(abs(px), abs(py)), abs(pz))
            cap = cutoff
            if SEED_POINT and not math.isnan(near_x):
                dx, dy, dz = px - near_x, py - near_y, pz - near_z
                cap = min(cap, math.sqrt(dx * dx + dy * dy + dz * dz) * (1.0 + BOX_SLACK) + BOX_SLACK * size)
            limit = max(cap, 0.0)
            # Each instance's lower bound, less its slack (see the module
            # docstring), for those whose sphere alone does not put them
            # beyond the cap (a comparison of squares, raised by 2^-40 over
            # the rounding of the bound, so that no instance the loop below
            # would visit is left out).
            found = 0
            for q in range(near.shape[0]):
                a = near[q]
                b = inst.box[a]
                c = inst.sphere[a]
                slack = inst.slack[a]
                margin = slack * max(size, b[6])
                sx, sy, sz = px - c[0], py - c[1], pz - c[2]
                centre = sx * sx + sy * sy + sz * sz
                reach = (limit * (1.0 + slack) + margin + c[3]) * (1.0 + BOX_SLACK)
                if centre > reach * reach:
                    continue
                dx = max(max(b[0] - px, px - b[3]), 0.0)
                dy = max(max(b[1] - py, py - b[4]), 0.0)
                dz = max(max(b[2] - pz, pz - b[5]), 0.0)
                low = max(math.sqrt(dx * dx + dy * dy + dz * dz), math.sqrt(centre) - c[3])
                lower[found] = (low - margin) / (1.0 + slack)
                pick[found] = a
                visit[found] = 0
                found += 1
            while True:
                # The nearest instance not yet visited: the first descent
                # usually finds the answer, after which few bounds are below it.
                bound = max(min(min(best, upper), cap), 0.0)
                q = -1
                low = math.inf
                for c in range(found):
                    if visit[c] == 0 and lower[c] < low:
                        q = c
                        low = lower[c]
                if q < 0 or low > bound:
                    break
                visit[q] = 1
                a = pick[q]
                r = inst.rotation[a]
                t = inst.translation[a]
                tx, ty, tz = px - t[0], py - t[1], pz - t[2]
                lx = tx * r[0, 0] + ty * r[1, 0] + tz * r[2, 0]
                ly = tx * r[0, 1] + ty * r[1, 1] + tz * r[2, 1]
                lz = tx * r[0, 2] + ty * r[1, 2] + tz * r[2, 2]
                proto = inst.prototype[a]
                before = best_index
                state = (
                    best, best_index, best_k, upper, lowest,
                    w_sqr, w_x, w_y, w_z, w_feature, w_a0, w_a1, w_a2, w_flag,
                )  # fmt: skip
                nan = math.nan
                state = DESCEND(
                    forest, roots[proto], stack_node, stack_sqr, lanes, z, magnitudes[proto],
                    lx, ly, lz, cap, nan, nan, nan, inst.offset[a], state,
                )  # fmt: skip
                best, best_index, best_k, upper, lowest = state[:5]
                w_sqr, w_x, w_y, w_z, w_feature, w_a0, w_a1, w_a2, w_flag = state[5:]
                if best_index != before:
                    winner = a
        if EXACT_FALLBACK:
            undecided[i] = min(best, upper) if lowest < math.inf and lowest <= min(best, cutoff) else math.nan
        if finite and (best > cutoff or (best_k < 0 and cutoff < math.inf)):
            no_answer(i, math.inf, full, dist, sqr, point, extra, feature, flag, prim)
            continue
        if best_k < 0:
            no_answer(i, math.nan, full, dist, sqr, point, extra, feature, flag, prim)
            continue
        dist[i] = best
        # The winner's closest point, back in the world (summed as rigid.to_world).
        r = inst.rotation[winner]
        t = inst.translation[winner]
        near_x = w_x * r[0, 0] + w_y * r[0, 1] + w_z * r[0, 2] + t[0]
        near_y = w_x * r[1, 0] + w_y * r[1, 1] + w_z * r[1, 2] + t[1]
        near_z = w_x * r[2, 0] + w_y * r[2, 1] + w_z * r[2, 2] + t[2]
        if full:
            sqr[i] = w_sqr
            point[i, 0], point[i, 1], point[i, 2] = near_x, near_y, near_z
            feature[i] = np.int8(w_feature)
            extra[i, 0] = w_a0
            extra[i, 1] = w_a1
            extra[i, 2] = w_a2
            flag[i] = w_flag
            prim[i] = best_index


@part
def _block_instances(block, inst, points, order, cutoff):
    """The instances that may hold the nearest primitive of a finite point of
    ``block``, in increasing order (see the module docstring)."""
    n = points.shape[0]
    m = inst.prototype.shape[0]
    lo_x, lo_y, lo_z = math.inf, math.inf, math.inf
    hi_x, hi_y, hi_z = -math.inf, -math.inf, -math.inf
    for j in range(block * BLOCK, min(n, (block + 1) * BLOCK)):
        i = order[j]
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        if math.isfinite(px) and math.isfinite(py) and math.isfinite(pz):
            lo_x, lo_y, lo_z = min(lo_x, px), min(lo_y, py), min(lo_z, pz)
            hi_x, hi_y, hi_z = max(hi_x, px), max(hi_y, py), max(hi_z, pz)
    if not lo_x <= hi_x:
        return np.empty(0, np.int64)
    size = max(max(max(-lo_x, hi_x), max(-lo_y, hi_y)), max(-lo_z, hi_z))
    # Every point of the box is within reach of every primitive of an
    # instance: the farthest corner from its sphere's centre, plus its
    # radius, raised by its slack.
    reach = cutoff
    for a in range(m):
        c = inst.sphere[a]
        fx = max(abs(lo_x - c[0]), abs(hi_x - c[0]))
        fy = max(abs(lo_y - c[1]), abs(hi_y - c[1]))
        fz = max(abs(lo_z - c[2]), abs(hi_z - c[2]))
        slack = inst.slack[a]
        far = math.sqrt(fx * fx + fy * fy + fz * fz) + c[3]
        reach = min(reach, (far + slack * max(size, inst.box[a, 6])) * (1.0 + slack))
    # The lower bound of each instance over the box, lowered as a point's is.
    near = np.empty(m, np.int64)
    count = 0
    for a in range(m):
        b = inst.box[a]
        dx = max(max(b[0] - hi_x, lo_x - b[3]), 0.0)
        dy = max(max(b[1] - hi_y, lo_y - b[4]), 0.0)
        dz = max(max(b[2] - hi_z, lo_z - b[5]), 0.0)
        c = inst.sphere[a]
        sx = max(max(lo_x - c[0], c[0] - hi_x), 0.0)
        sy = max(max(lo_y - c[1], c[1] - hi_y), 0.0)
        sz = max(max(lo_z - c[2], c[2] - hi_z), 0.0)
        low = max(math.sqrt(dx * dx + dy * dy + dz * dz), math.sqrt(sx * sx + sy * sy + sz * sz) - c[3])
        slack = inst.slack[a]
        if not (low - slack * max(size, b[6])) / (1.0 + slack) > reach:
            near[count] = a
            count += 1
    return near[:count]


def _loop(handle, lo, hi, forest, roots, magnitudes, depth, inst, points, order, out, full, cutoff):
    """:func:`_instances_block` for the blocks of points ``lo .. hi - 1``."""
    for block in range(lo, hi):
        args = (forest, roots, magnitudes, depth, inst, points, order, out, full, cutoff)
        CALL(handle, block, *args)


def _blocks(forest, roots, magnitudes, depth, inst, points, *args):
    """The number of blocks of :func:`_loop`."""
    return (points.shape[0] + BLOCK - 1) // BLOCK


@functools.cache
def instances_kernel(method, present, radius=-1, indexed=False):
    """The compiled instanced search of ``method`` over forests of the kinds ``present``
    (``indexed``: one tree of faces read through their vertices)."""
    names = "_".join(p.name for p in present) + ("_rounded" if radius >= 0 else "")
    tag = method.name + ("_indexed" if indexed else "")
    block_signature, loop_signature = _SIGNATURES[indexed]
    block = specialize(
        _instances_block,
        f"{tag}__{names}",
        block_signature,
        role="pointer",
        DESCEND=descent(method, present, radius, indexed),
        SEED_POINT=not method.loose,
        EXACT_FALLBACK=method.exact_fallback,
    )
    loop = "instances_indexed" if indexed else "instances"
    return launcher(_loop, loop, loop_signature, block, block_signature, _blocks, SEARCH_GRAIN)


#: The rows of trees of faces read through their vertices, gathered once for
#: the forests of several trees that they join (a forest is made per query).
_ROWS = weakref.WeakKeyDictionary()


def _rows(tree):
    """:attr:`.tree.Tree.params` of ``tree``, kept while it lives where it is gathered."""
    if not tree.indexed:
        return tree.params
    rows = _ROWS.get(tree)
    if rows is None:
        rows = _ROWS[tree] = tree.params
    return rows


def forest(trees, loose=False, cull=True):
    """The prototypes' trees as one: ``(TreeArrays, roots, magnitudes, depth,
    radius column)``; one tree is used as it is, several are concatenated
    (their nodes and rows renumbered), rows padded to one width.
    ``cull=False``: without the primitives' cull rows (see
    :meth:`.tree.Tree.boxes`)."""
    boxes = [tree.boxes(loose, cull) for tree in trees]
    if len(trees) == 1:
        (tree,), (bounds, cull, magnitude) = trees, boxes[0]
        arrays = TreeArrays(tree.kinds, tree.rows(), tree.index, cull, bounds, tree.child, tree.count)
        return arrays, readonly([0], np.int64), readonly([magnitude], np.float64), tree.depth, tree.radius
    width = max(tree.width for tree in trees)
    kinds, params, index, cull, bounds, child, count = [], [], [], [], [], [], []
    roots, magnitudes = [], []
    nodes = rows = 0
    for tree, (b, c, magnitude) in zip(trees, boxes, strict=True):
        roots.append(nodes)
        magnitudes.append(magnitude)
        kinds.append(tree.kinds)
        rows_of_tree = _rows(tree)
        p = np.zeros((len(rows_of_tree), width))
        p[:, : rows_of_tree.shape[1]] = rows_of_tree
        params.append(p)
        index.append(tree.index)
        cull.append(c[:, :CULL_COLUMNS])
        bounds.append(b)
        leaf = tree.count > 0
        child.append(np.where(leaf, tree.child.astype(np.int64) + rows, tree.child.astype(np.int64) + nodes))
        count.append(tree.count)
        nodes += len(tree.child)
        rows += len(tree.kinds)
    ro = readonly
    arrays = TreeArrays(
        ro(np.concatenate(kinds), np.int8), ro(np.concatenate(params), np.float64),
        indices(np.concatenate(index)), ro(np.concatenate(cull), np.float32),
        ro(np.concatenate(bounds), np.float64), indices(np.concatenate(child)),
        indices(np.concatenate(count)),
    )  # fmt: skip
    radius = width - 1 if width > primitives.N_PARAMS else -1
    depth = max(tree.depth for tree in trees)
    return arrays, ro(roots, np.int64), ro(magnitudes, np.float64), depth, radius


def instance_arrays(trees, prototype, rotation, translation, offset, loose=False):
    """The :data:`InstanceArrays` of instances of ``trees[prototype]`` posed by
    ``(rotation, translation)``: their world boxes are the prototypes' root
    boxes moved (eight corners, the box around them, widened by
    :data:`BOX_SLACK` of their magnitude), their spheres the prototypes'
    (:meth:`.tree.Tree.sphere`) moved."""
    roots = np.array([tree.boxes(loose, False)[0][0, :6] for tree in trees])[prototype]
    spheres = [tree.sphere(loose) for tree in trees]
    centre = np.array([c for c, _ in spheres]).reshape(-1, 3)[prototype]
    radius = np.array([r for _, r in spheres])[prototype]
    corners = np.stack(
        [roots[:, [3 * (c & 1), 1 + 3 * ((c >> 1) & 1), 2 + 3 * ((c >> 2) & 1)]] for c in range(8)], axis=1
    )
    with np.errstate(invalid="ignore", over="ignore"):
        world = _moved(corners, rotation, translation)
        low, high = world.min(axis=1), world.max(axis=1)
        local = np.abs(roots).max(axis=1)
        magnitude = np.maximum(np.maximum(np.abs(low).max(axis=1), np.abs(high).max(axis=1)), local)
        widen = (BOX_SLACK * magnitude)[:, None]
        moved = _moved(centre[:, None], rotation, translation)[:, 0]
        error = np.abs(np.swapaxes(rotation, -1, -2) @ rotation - np.eye(3)).max(axis=(-1, -2), initial=0.0)
    box = np.concatenate([low - widen, high + widen, magnitude[:, None]], axis=1)
    box = np.where(np.isfinite(box), box, np.where(np.arange(7) < 3, -np.inf, np.inf))
    sphere = np.concatenate([moved, radius[:, None]], axis=1)
    sphere = np.where(np.isfinite(sphere).all(axis=1, keepdims=True), sphere, [0.0, 0.0, 0.0, np.inf])
    slack = BOX_SLACK + 4.0 * np.where(np.isfinite(error), error, np.inf)
    ro = readonly
    return InstanceArrays(
        ro(prototype, np.int64), ro(rotation, np.float64), ro(translation, np.float64),
        ro(box, np.float64), ro(sphere, np.float64), ro(slack, np.float64), ro(offset, np.int64),
    )  # fmt: skip


def _moved(corners, rotation, translation):
    """Corners ``(n, 8, 3)``, those of instance ``i`` moved by its pose (summed as
    :func:`proximity.numerics.rigid.to_world` sums)."""
    out = np.empty_like(corners)
    for a in range(3):
        out[..., a] = (
            corners[..., 0] * rotation[:, None, a, 0]
            + corners[..., 1] * rotation[:, None, a, 1]
            + corners[..., 2] * rotation[:, None, a, 2]
            + translation[:, None, a]
        )
    return out


def nearest_instances(trees, instances, method, points, full, loose=False, cutoff=math.inf):
    """Nearest primitive of any instance to each of the validated points ``(n, 3)``.

    ``trees`` are the prototypes' trees, ``instances`` an :data:`InstanceArrays`
    (from :func:`instance_arrays`).  Returns the outputs of
    :func:`.nearest.nearest`, ``index`` numbering the instances' primitives
    one after the other (``instances.offset``).
    """
    from .nearest import _visiting_order

    points = readonly(points, np.float64)
    n = points.shape[0]
    order = readonly(_visiting_order(points), np.int64)  # before the outputs, as nearest's
    out = new_outputs(n, full, method.exact_fallback)
    present = {p.code: p for tree in trees for p in tree.present}
    present = tuple(present[code] for code in sorted(present))
    kinds = present if len(present) == 1 else primitives.offering(method)
    # The radius column forest gives: any tree's (its rows are padded to one width).
    culls = reads_cull(method, kinds, max(tree.radius for tree in trees))
    arrays, roots, magnitudes, depth, radius = forest(tuple(trees), loose, culls)
    search = instances_kernel(method, kinds, radius, len(trees) == 1 and trees[0].indexed)
    search(arrays, roots, magnitudes, depth, instances, points, order, out, full, float(cutoff))
    rows = np.flatnonzero(~np.isnan(out.undecided))
    if len(rows):
        _resolve(trees, instances, rows, points, out, full, loose, cutoff)
    result = out._asdict()
    del result["undecided"]
    return result


def _resolve(trees, instances, rows, points, out, full, loose, cutoff):
    """Rows whose nearest primitive may be an undecided certified answer:
    each instance near enough resolves its candidates in its own frame
    (:func:`.nearest._resolve` on a copy of the row), the least wins."""
    from ..numerics.rigid import to_local, to_world
    from .nearest import _resolve as resolve_tree

    for i in rows:
        bound = out.undecided[i]
        best = None
        for a in range(len(instances.prototype)):
            b = instances.box[a]
            p = points[i]
            gap = np.sqrt(np.sum(np.maximum(np.maximum(b[:3] - p, p - b[3:6]), 0.0) ** 2))
            slack = instances.slack[a]
            if gap > max(bound, 0.0) * (1 + slack) + slack * max(np.abs(p).max(), b[6]):
                continue
            tree = trees[instances.prototype[a]]
            local = readonly(to_local(p[None], instances.rotation[a], instances.translation[a]), np.float64)
            one = Outputs(*(np.array(getattr(out, f)[i : i + 1] if f != "undecided" else [bound])
                            for f in Outputs._fields))  # fmt: skip
            one.distance[0] = math.inf
            if full:
                one.index[0] = -1
            bounds, cull, magnitude = tree.boxes(loose)
            resolve_tree(tree, np.array([0]), local, one, full, cull, bounds, magnitude, cutoff)
            d = one.distance[0]
            idx = one.index[0] + instances.offset[a] if full else 0
            if not np.isfinite(d) and not (d == math.inf):
                continue
            if best is None or (d, idx) < (best[0], best[1]):
                best = (d, idx, a, one)
        if best is None:
            continue
        d, idx, a, one = best
        out.distance[i] = d
        if full and np.isfinite(d):
            out.index[i] = idx
            out.point[i] = to_world(one.point[0], instances.rotation[a], instances.translation[a])
            for name in ("sqr_distance", "feature", "extra", "flag"):
                getattr(out, name)[i] = getattr(one, name)[0]

/* Closest-hit and any-hit traversal of the flattened BVH (see types.h for the node layout). */
#ifndef SPECTRACE_BVH_CL
#define SPECTRACE_BVH_CL

#include "types.h"
#include "scene_features.h"
#include "triangle.cl"
#include "triangle_blocks.cl"

/* BVH_STACK_SIZE, BVH4_STACK_SIZE, BVH8_STACK_SIZE: the traversal stacks' entries, from the depth the host's builder
 * guarantees (MAX_DEPTH; the collapse in geometry/bvh4.py), set in spectrace.core.contract and passed as build
 * defines. */

typedef struct {
    float t;         /* distance along the ray; t_max when nothing was hit */
    int triangle;    /* slot in the triangle arrays, or -1 */
    float2 b12;      /* barycentric coordinates of v1 and v2 */
#if SCENE_HAS_INSTANCES
    int instance;    /* the Instance whose object the triangle belongs to, or -1 for the scene's own surfaces */
#endif
} Hit;

/* Distance at which the ray enters the box, or INFINITY when it misses it before t_max. The exit distance is widened by 2γ₃
 * (Ize 2013, "Robust BVH Ray Traversal") so rounding never rejects a box the ray touches, e.g. a flat box
 * hit exactly on its edge, where a shared triangle edge lies. */
inline float ray_box_entry(__global const BVHNode *node, float3 origin, float3 inv_direction, float t_max)
{
    float3 lo = ((float3)(node->bmin[0], node->bmin[1], node->bmin[2]) - origin) * inv_direction;
    float3 hi = ((float3)(node->bmax[0], node->bmax[1], node->bmax[2]) - origin) * inv_direction;
    float3 near = fmin(lo, hi), far = fmax(lo, hi);
    float enter = fmax(fmax(near.x, near.y), fmax(near.z, 0.0f));
    float leave = fmin(fmin(far.x, far.y), far.z) * 1.0000004f;
    leave = fmin(leave, t_max);
    return enter <= leave ? enter : INFINITY;
}

/* What both traversals precompute for a ray. A zero direction component would give 0 * inf = NaN for an origin on
 * a slab plane; a tiny one of the same sign keeps every product finite and treats the ray as leaning to that side,
 * which the edge-inclusive triangle test agrees with. */
typedef struct {
    float3 inv_direction;
    float4 origin4;
    float3 origin_k;  /* the origin's coordinates in the shear's axis order, for the 4-triangle leaf test */
    RayShear shear;
} TraversalRay;

/* 1 / direction for the slab tests, with components below 1e-30 in size taken as ±1e-30 (same sign), so a ray
 * parallel to a slab gets a huge finite reciprocal rather than inf times 0 = NaN at the box's faces. */
inline float3 slab_inverse_direction(float3 direction)
{
    float3 tiny = copysign((float3)(1.0e-30f), direction);
    return 1.0f / select(direction, tiny, fabs(direction) < (float3)(1.0e-30f));
}

inline TraversalRay traversal_ray(Ray ray)
{
    TraversalRay r;
    r.inv_direction = slab_inverse_direction(ray.direction);
    r.origin4 = (float4)(ray.origin, 0.0f);
    r.shear = ray_shear(ray.direction);
    r.origin_k = shuffle(r.origin4, r.shear.permutation).xyz;
    return r;
}

inline Hit no_hit(float t_max)
{
    Hit hit;
    hit.t = t_max;
    hit.triangle = -1;
    hit.b12 = (float2)(0.0f);
#if SCENE_HAS_INSTANCES
    hit.instance = -1;
#endif
    return hit;
}

/* Tests the leaf's triangles [first, first + count) and keeps the closest hit before hit->t; returns 1 when an
 * any-hit query is answered. */
inline int intersect_leaf(__global const float4 *triangle_vertices, const TraversalRay *r, int first, int count,
                          int any_hit, Hit *hit)
{
    for (int i = first; i < first + count; ++i) {
        float2 b12;
        float t = intersect_triangle(r->origin4, &r->shear, triangle_vertices[3 * i], triangle_vertices[3 * i + 1],
                                     triangle_vertices[3 * i + 2], hit->t, &b12);
        if (t < hit->t) {
            hit->t = t;
            hit->triangle = i;
            hit->b12 = b12;
            if (any_hit) return 1;
        }
    }
    return 0;
}

/* BVH4_STACK_SIZE: up to three pushes per 4-wide level, over at most MAX_DEPTH levels (geometry/bvh4.py). A larger
 * stack than needed measured no slower than a 96-entry one on either CPU runtime. */

/* Orders two (entry, reference) pairs by entry: one compare-exchange of the sorting network below. */
#define BVH4_ORDER(ta, ra, tb, rb)                                                 \
    {                                                                              \
        if (tb < ta) {                                                             \
            float t_swap = ta; ta = tb; tb = t_swap;                               \
            int r_swap = ra; ra = rb; rb = r_swap;                                 \
        }                                                                          \
    }

/* 4-wide traversal (types.h BVH4Node): one visit slab-tests the four children's boxes as float4, sorts the hit ones
 * near to far with a 5-comparator network, enters the nearest and pushes the rest with their entry distances. A
 * leaf is a run of blocks of four triangles (triangle_blocks.cl) after the nodes in the same buffer. Stack references: a
 * 4-wide node index (>= 0), or ~(float4 offset of a leaf's first block in the node buffer). */
inline Hit trace_bvh4(__global const BVH4Node *nodes, __global const float4 *triangle_vertices, Ray ray,
                      float t_max, int any_hit)
{
    Hit hit = no_hit(t_max);
    TraversalRay r = traversal_ray(ray);
    float3 inv_direction = r.inv_direction;
    float4 ox = (float4)(ray.origin.x), oy = (float4)(ray.origin.y), oz = (float4)(ray.origin.z);
    float4 ix = (float4)(inv_direction.x), iy = (float4)(inv_direction.y), iz = (float4)(inv_direction.z);
    int stack[BVH4_STACK_SIZE];
    float stack_entry[BVH4_STACK_SIZE];
    int top = 0;
    int reference = 0;
    while (true) {
        if (reference < 0) {
            __global const float4 *block = (__global const float4 *)nodes + ~reference;
            while (true) {
                int4 meta = as_int4(block[LEAF_BLOCK_FLOAT4S - 1]);
                if (intersect_triangles4(block, r.origin_k, &r.shear, meta, &hit.t, &hit.triangle, &hit.b12)
                    && any_hit) {
                    return hit;
                }
                if (!meta.z) break;
                block += LEAF_BLOCK_FLOAT4S;
            }
        } else {
            __global const BVH4Node *node = &nodes[reference];
            float4 lx = (node->child_min[0] - ox) * ix, hx = (node->child_max[0] - ox) * ix;
            float4 ly = (node->child_min[1] - oy) * iy, hy = (node->child_max[1] - oy) * iy;
            float4 lz = (node->child_min[2] - oz) * iz, hz = (node->child_max[2] - oz) * iz;
            float4 enter = fmax(fmax(fmin(lx, hx), fmin(ly, hy)), fmax(fmin(lz, hz), (float4)(0.0f)));
            /* Exit widened by 2γ₃ as in ray_box_entry (Ize 2013). */
            float4 leave = fmin(fmin(fmax(lx, hx), fmax(ly, hy)), fmax(lz, hz)) * 1.0000004f;
            leave = fmin(leave, (float4)(hit.t));
            int4 counts = node->count;
            int4 entered = (enter <= leave) & (counts >= (int4)(0));
            float4 t4 = select((float4)(INFINITY), enter, entered);
            int4 child = node->child;
            int4 refs = select(child, ~child, counts > (int4)(0));
            float t0 = t4.s0, t1 = t4.s1, t2 = t4.s2, t3 = t4.s3;
            int r0 = refs.s0, r1 = refs.s1, r2 = refs.s2, r3 = refs.s3;
            BVH4_ORDER(t0, r0, t1, r1);
            BVH4_ORDER(t2, r2, t3, r3);
            BVH4_ORDER(t0, r0, t2, r2);
            BVH4_ORDER(t1, r1, t3, r3);
            BVH4_ORDER(t1, r1, t2, r2);
            if (t0 != INFINITY) {
                if (t3 != INFINITY) { stack[top] = r3; stack_entry[top] = t3; ++top; }
                if (t2 != INFINITY) { stack[top] = r2; stack_entry[top] = t2; ++top; }
                if (t1 != INFINITY) { stack[top] = r1; stack_entry[top] = t1; ++top; }
                reference = r0;
                continue;
            }
        }
        while (true) {
            if (top == 0) return hit;
            --top;
            if (stack_entry[top] <= hit.t) { reference = stack[top]; break; }
        }
    }
}

/* What the 8-wide traversal keeps of a ray for its slab tests: the origin and 1 / direction in every lane, and of
 * each axis the plane a box is entered by (0..2 the lower planes x, y, z, 3..5 the upper ones): the lower one when
 * the direction is positive, else the upper one, as fmin and fmax of the two would pick, with the same values, since
 * a valid box's planes keep their order through the subtraction and the product. */
typedef struct {
    float8 ox, oy, oz;
    float8 ix, iy, iz;
    int near_x, near_y, near_z, far_x, far_y, far_z;
} BVH8Ray;

/* A node's eight children against the ray: the distances to each axis's entry (n) and exit (f) planes. */
typedef struct {
    float8 nx, fx, ny, fy, nz, fz;
} BVH8Slabs;

/* The node decode, the one place the two 8-wide node formats differ. The build define BVH8_QUANTISED picks it rather
 * than an argument: PoCL optimises the traversal before its kernel compiler inlines it, and would keep both
 * decodes in the loop. */
#if defined(BVH8_QUANTISED)
/* types.h BVH8QNode: a child's planes are origin + q * scale, the product exact (scale is a power of two), one
 * rounding in the sum, as the host's quantise_nodes computes it. The quantised planes contain the float boxes, so
 * the traversal visits every child the float nodes would have it visit and finds the same closest hit, save which
 * of equally near triangles wins when the visiting order differs. */
inline BVH8Slabs bvh8_slabs(__global const float4 *nodes, int reference, const BVH8Ray *r)
{
    __global const BVH8QNode *node = (__global const BVH8QNode *)nodes + reference;
    __global const uchar8 *q = node->q;
    float8 px = (float8)(node->origin[0]), py = (float8)(node->origin[1]), pz = (float8)(node->origin[2]);
    float8 sx = (float8)(node->scale[0]), sy = (float8)(node->scale[1]), sz = (float8)(node->scale[2]);
    BVH8Slabs d;
    d.nx = (px + convert_float8(q[r->near_x]) * sx - r->ox) * r->ix;
    d.fx = (px + convert_float8(q[r->far_x]) * sx - r->ox) * r->ix;
    d.ny = (py + convert_float8(q[r->near_y]) * sy - r->oy) * r->iy;
    d.fy = (py + convert_float8(q[r->far_y]) * sy - r->oy) * r->iy;
    d.nz = (pz + convert_float8(q[r->near_z]) * sz - r->oz) * r->iz;
    d.fz = (pz + convert_float8(q[r->far_z]) * sz - r->oz) * r->iz;
    return d;
}

inline int8 bvh8_kind(__global const float4 *nodes, int reference)
{
    return convert_int8(((__global const BVH8QNode *)nodes)[reference].kind);
}

inline int8 bvh8_child(__global const float4 *nodes, int reference)
{
    return ((__global const BVH8QNode *)nodes)[reference].child;
}
#else
/* types.h BVH8Node: the planes as stored, child_min[0..2] then child_max[0..2]. */
inline BVH8Slabs bvh8_slabs(__global const float4 *nodes, int reference, const BVH8Ray *r)
{
    __global const float8 *planes = ((__global const BVH8Node *)nodes)[reference].child_min;
    BVH8Slabs d;
    d.nx = (planes[r->near_x] - r->ox) * r->ix, d.fx = (planes[r->far_x] - r->ox) * r->ix;
    d.ny = (planes[r->near_y] - r->oy) * r->iy, d.fy = (planes[r->far_y] - r->oy) * r->iy;
    d.nz = (planes[r->near_z] - r->oz) * r->iz, d.fz = (planes[r->far_z] - r->oz) * r->iz;
    return d;
}

inline int8 bvh8_kind(__global const float4 *nodes, int reference)
{
    return ((__global const BVH8Node *)nodes)[reference].count;
}

inline int8 bvh8_child(__global const float4 *nodes, int reference)
{
    return ((__global const BVH8Node *)nodes)[reference].child;
}
#endif

/* 8-wide traversal (types.h BVH8Node, or BVH8QNode with BVH8_QUANTISED: bvh8_slabs above), for CPUs whose vectors
 * hold eight floats: one visit slab-tests the eight children's boxes as float8; the hit ones go onto the stack by
 * insertion, farthest deepest, and the nearest is popped and entered at once. A leaf is a run of blocks of eight
 * triangles (triangle_blocks.cl) after the nodes in the same buffer. Stack references as in trace_bvh4: a node index
 * (>= 0), or ~(float4 offset of a leaf's first block). BVH8_STACK_SIZE entries of 8 bytes (96: 768 bytes of private
 * memory): the collapse bounds the entries a path pushes to fit (bvh4.py collapse, stack_size). */
inline Hit trace_bvh8(__global const float4 *nodes, __global const float4 *triangle_vertices, Ray ray, float t_max,
                      int any_hit)
{
    Hit hit = no_hit(t_max);
    TraversalRay r = traversal_ray(ray);
    float3 inv_direction = r.inv_direction;
    BVH8Ray r8;
    r8.ox = (float8)(ray.origin.x), r8.oy = (float8)(ray.origin.y), r8.oz = (float8)(ray.origin.z);
    r8.ix = (float8)(inv_direction.x), r8.iy = (float8)(inv_direction.y), r8.iz = (float8)(inv_direction.z);
    r8.near_x = inv_direction.x >= 0.0f ? 0 : 3, r8.near_y = inv_direction.y >= 0.0f ? 1 : 4;
    r8.near_z = inv_direction.z >= 0.0f ? 2 : 5;
    r8.far_x = r8.near_x ^ 3, r8.far_y = r8.near_y == 1 ? 4 : 1, r8.far_z = r8.near_z == 2 ? 5 : 2;
    int stack[BVH8_STACK_SIZE];
    float stack_entry[BVH8_STACK_SIZE];
    int top = 0;
    int reference = 0;
    while (true) {
        if (reference < 0) {
            __global const float8 *block = (__global const float8 *)(nodes + ~reference);
            while (true) {
                int4 meta = as_int4(block[LEAF_BLOCK8_FLOAT8S - 1].lo);
                if (intersect_triangles8(block, r.origin_k, &r.shear, meta, &hit.t, &hit.triangle, &hit.b12)
                    && any_hit) {
                    return hit;
                }
                if (!meta.z) break;
                block += LEAF_BLOCK8_FLOAT8S;
            }
        } else {
            BVH8Slabs d = bvh8_slabs(nodes, reference, &r8);
            float8 enter = fmax(fmax(d.nx, d.ny), fmax(d.nz, (float8)(0.0f)));
            /* Exit widened by 2γ₃ as in ray_box_entry (Ize 2013). */
            float8 leave = fmin(fmin(d.fx, d.fy), d.fz) * 1.0000004f;
            leave = fmin(leave, (float8)(hit.t));
            int8 kind = bvh8_kind(nodes, reference);
            int8 entered = (enter <= leave) & (kind >= (int8)(0));
            if (any(entered)) {
                int8 child = bvh8_child(nodes, reference);
                int refs[8];
                float entries[8];
                vstore8(select(child, ~child, kind > (int8)(0)), 0, refs);
                vstore8(select((float8)(INFINITY), enter, entered), 0, entries);
                int base = top;
                for (int k = 0; k < 8; ++k) {
                    float t = entries[k];
                    if (t == INFINITY) continue;
                    /* Insertion keeping [base, top) farthest first; equal entries keep the lower slot nearer the
                     * top, so it is visited first. */
                    int j = top;
                    while (j > base && stack_entry[j - 1] <= t) {
                        stack[j] = stack[j - 1];
                        stack_entry[j] = stack_entry[j - 1];
                        --j;
                    }
                    stack[j] = refs[k];
                    stack_entry[j] = t;
                    ++top;
                }
                --top;
                reference = stack[top];
                continue;
            }
        }
        while (true) {
            if (top == 0) return hit;
            --top;
            if (stack_entry[top] <= hit.t) { reference = stack[top]; break; }
        }
    }
}

/* A walk over a binary BVH whose leaves the caller tests (triangles, analytic shapes, instances): at an inner
 * node the children the ray enters are visited near to far, the farther one kept on a stack with the distance at
 * which the ray enters its box. Every binary traversal in the kernels takes its steps from here. */
typedef struct {
    int stack[BVH_STACK_SIZE];
    float entry[BVH_STACK_SIZE];  /* where the ray enters each pushed node's box */
    int top;
    int index;                    /* the node the walk stands at */
} BinaryWalk;

/* At the root; 0 when the ray misses the whole BVH before t_max. */
inline int binary_walk_start(BinaryWalk *walk, __global const BVHNode *nodes, float3 origin, float3 inv_direction,
                             float t_max)
{
    walk->top = 0;
    walk->index = 0;
    return ray_box_entry(&nodes[0], origin, inv_direction, t_max) != INFINITY;
}

/* Pop, skipping nodes that a closer hit found since has made irrelevant (t: the closest hit so far). Entering
 * before t is the whole test: the box's exit was checked against a t_max no smaller than t when it was pushed.
 * 0 when the stack is empty: the walk is over. */
inline int binary_walk_pop(BinaryWalk *walk, float t)
{
    while (walk->top > 0) {
        --walk->top;
        if (walk->entry[walk->top] <= t) {
            walk->index = walk->stack[walk->top];
            return 1;
        }
    }
    return 0;
}

/* From the node the walk stands at, down to the next leaf the ray may meet before t: 1 with walk->index at that
 * leaf, 0 when the walk is over. After testing the leaf, the caller pops (binary_walk_pop) and descends again. */
inline int binary_walk_to_leaf(BinaryWalk *walk, __global const BVHNode *nodes, float3 origin, float3 inv_direction,
                               float t)
{
    while (true) {
        __global const BVHNode *node = &nodes[walk->index];
        if (node->count > 0) return 1;
        int left = node->left_first;
        float t_left = ray_box_entry(&nodes[left], origin, inv_direction, t);
        float t_right = ray_box_entry(&nodes[left + 1], origin, inv_direction, t);
        if (t_left != INFINITY || t_right != INFINITY) {
            if (fmax(t_left, t_right) != INFINITY) {
                walk->stack[walk->top] = t_left <= t_right ? left + 1 : left;
                walk->entry[walk->top] = fmax(t_left, t_right);
                ++walk->top;
            }
            walk->index = t_left <= t_right ? left : left + 1;
            continue;
        }
        if (!binary_walk_pop(walk, t)) return 0;
    }
}

/* any_hit: stop at the first hit closer than t_max (shadow rays).
 * Both children's boxes are tested from the parent and the nearer is entered first; the farther one is pushed
 * with its entry distance, so a pop drops it without reading its box again once a closer hit is known.
 * Scalar reads of the node on purpose: reading it as two float4, or carrying the child's node data down from the
 * parent's test, measured slower on at least one CPU runtime (docs/performance.md). */
inline Hit trace_bvh_binary(__global const BVHNode *nodes, __global const float4 *triangle_vertices, Ray ray,
                            float t_max, int any_hit)
{
    Hit hit = no_hit(t_max);
    TraversalRay r = traversal_ray(ray);
    BinaryWalk walk;
    if (!binary_walk_start(&walk, nodes, ray.origin, r.inv_direction, t_max)) return hit;
    while (binary_walk_to_leaf(&walk, nodes, ray.origin, r.inv_direction, hit.t)) {
        __global const BVHNode *node = &nodes[walk.index];
        if (intersect_leaf(triangle_vertices, &r, node->left_first, node->count, any_hit, &hit)) return hit;
        if (!binary_walk_pop(&walk, hit.t)) break;
    }
    return hit;
}

/* The traversal the build selected: BVH_WIDTH == 8 or 4 when the host uploaded 8- or 4-wide nodes
 * (geometry/bvh4.py) in the node buffer, quantised 8-wide ones when BVH8_QUANTISED is defined too, whose kernel arguments keep the binary node type. */
inline Hit trace_bvh(__global const BVHNode *nodes, __global const float4 *triangle_vertices, Ray ray, float t_max,
                     int any_hit)
{
#if defined(BVH_WIDTH) && BVH_WIDTH == 8
    return trace_bvh8((__global const float4 *)nodes, triangle_vertices, ray, t_max, any_hit);
#elif defined(BVH_WIDTH) && BVH_WIDTH == 4
    return trace_bvh4((__global const BVH4Node *)nodes, triangle_vertices, ray, t_max, any_hit);
#else
    return trace_bvh_binary(nodes, triangle_vertices, ray, t_max, any_hit);
#endif
}

#endif

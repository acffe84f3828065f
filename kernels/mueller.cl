/* Stokes vectors and Mueller matrices at a path's four wavelengths, for polarised transport (SCENE_POLARIZED).
 *
 * Sources: E. Collett, "Field Guide to Polarization" (SPIE, 2005): the Stokes parameters, the Mueller matrices of
 * the rotator, the linear diattenuator (polariser) and the linear retarder; M. Born & E. Wolf, "Principles of
 * Optics", Sec. 1.5 (Fresnel amplitude coefficients, fresnel_polarized.cl); Mitsuba 3's documentation, developer
 * guide "Polarization" (a Stokes vector is meaningful only with the reference basis it is expressed in, which
 * travels with the ray and is turned into each element's own basis at every interaction).
 *
 * Convention: a beam travelling along the unit vector k has its Stokes vector (S0, S1, S2, S3) in a reference basis
 * (x, y = k × x), x a unit vector normal to k. S1 > 0: linear polarisation along x; S2 > 0: along (x + y)/√2;
 * S3 > 0: right-circular in Collett's sense, the field turning from y toward x (clockwise to one who looks into the
 * beam toward its source), Collett's time dependence exp(i(ωt − kz)); Mitsuba 3's Stokes vectors are the same.
 * Units: S0..S3 carry the unit of the radiance they describe; Mueller matrices are dimensionless.
 *
 * Layout: each entry is a float4 of the four wavelengths' values; a matrix is 16 of them, row-major
 * (m[4 * row + column]). Every element the kernels know has, in its own basis, the form of a linear diattenuator
 * and retarder aligned with x (Collett, "Mueller matrices"):
 *     | a  b  0  0 |
 *     | b  a  0  0 |
 *     | 0  0  c  d |
 *     | 0  0 -d  c |
 * a polariser (a, b = (k1 ± k2)/2, c = √(k1 k2), d = 0), a retarder (1, 0, cos δ, sin δ), Fresnel reflection and
 * transmission in the s/p basis; AlignedElement holds its four entries. */
#ifndef SPECTRACE_MUELLER_CL
#define SPECTRACE_MUELLER_CL

typedef struct {
    float4 m[16];
} Mueller;

/* The diattenuator-retarder aligned with its basis' x axis (the matrix above). */
typedef struct {
    float4 a, b, c, d;
} AlignedElement;

inline Mueller mueller_identity(void)
{
    Mueller r;
    for (int i = 0; i < 16; ++i) r.m[i] = (float4)(i % 5 == 0 ? 1.0f : 0.0f);
    return r;
}

/* (cos 2θ, sin 2θ) of the angle θ from basis vector x_from to x_to, both normal to the beam's direction k, counted
 * from x_from toward k × x_from. */
inline float2 stokes_basis_turn(float3 k, float3 x_from, float3 x_to)
{
    float c = dot(x_from, x_to);
    float s = dot(cross(k, x_from), x_to);
    float n = c * c + s * s;
    if (!(n > 0.0f)) return (float2)(1.0f, 0.0f);
    return (float2)((c * c - s * s) / n, 2.0f * c * s / n);
}

/* a · R, R re-expressing a Stokes vector given in a basis x into the basis turned by θ from x (turn: cos 2θ,
 * sin 2θ): S1' = cos 2θ S1 + sin 2θ S2, S2' = −sin 2θ S1 + cos 2θ S2. Only a's columns 1 and 2 change. */
inline void mueller_then_rotate(Mueller *a, float2 turn)
{
    for (int i = 0; i < 4; ++i) {
        float4 c1 = a->m[4 * i + 1], c2 = a->m[4 * i + 2];
        a->m[4 * i + 1] = turn.x * c1 - turn.y * c2;
        a->m[4 * i + 2] = turn.y * c1 + turn.x * c2;
    }
}

/* a · E for an aligned element E. */
inline void mueller_then_element(Mueller *a, const AlignedElement *e)
{
    for (int i = 0; i < 4; ++i) {
        float4 c0 = a->m[4 * i], c1 = a->m[4 * i + 1], c2 = a->m[4 * i + 2], c3 = a->m[4 * i + 3];
        a->m[4 * i] = c0 * e->a + c1 * e->b;
        a->m[4 * i + 1] = c0 * e->b + c1 * e->a;
        a->m[4 * i + 2] = c2 * e->c - c3 * e->d;
        a->m[4 * i + 3] = c2 * e->d + c3 * e->c;
    }
}

/* a · b for any b. */
inline void mueller_then_matrix(Mueller *a, const Mueller *b)
{
    for (int i = 0; i < 4; ++i) {
        float4 r0 = a->m[4 * i], r1 = a->m[4 * i + 1], r2 = a->m[4 * i + 2], r3 = a->m[4 * i + 3];
        for (int j = 0; j < 4; ++j)
            a->m[4 * i + j] = r0 * b->m[j] + r1 * b->m[4 + j] + r2 * b->m[8 + j] + r3 * b->m[12 + j];
    }
}

/* The aligned element e as a matrix. */
inline Mueller mueller_from_aligned(const AlignedElement *e)
{
    Mueller r;
    for (int i = 0; i < 16; ++i) r.m[i] = (float4)(0.0f);
    r.m[0] = r.m[5] = e->a;
    r.m[1] = r.m[4] = e->b;
    r.m[10] = r.m[15] = e->c;
    r.m[11] = e->d;
    r.m[14] = -e->d;
    return r;
}

/* a · D, D the ideal depolariser diag(1, 0, 0, 0): only the response to unpolarised light (column 0) remains. */
inline void mueller_then_depolarize(Mueller *a)
{
    for (int i = 0; i < 4; ++i) {
        a->m[4 * i + 1] = (float4)(0.0f);
        a->m[4 * i + 2] = (float4)(0.0f);
        a->m[4 * i + 3] = (float4)(0.0f);
    }
}

/* Divides every entry by s (lanes where s is not positive become 0). */
inline void mueller_scale(Mueller *a, float4 s)
{
    float4 inverse = select((float4)(0.0f), 1.0f / s, s > (float4)(0.0f));
    for (int i = 0; i < 16; ++i) a->m[i] *= inverse;
}

/* The linear polariser with transmittances k1 along x and k2 across it (k2 / k1: its extinction). */
inline AlignedElement linear_polarizer_element(float4 k1, float4 k2)
{
    AlignedElement e;
    e.a = 0.5f * (k1 + k2);
    e.b = 0.5f * (k1 - k2);
    e.c = sqrt(fmax(k1 * k2, 0.0f));
    e.d = (float4)(0.0f);
    return e;
}

/* The linear retarder of retardance delta (radians) with its fast axis along x, transmitting t. */
inline AlignedElement linear_retarder_element(float delta, float4 t)
{
    AlignedElement e;
    e.a = t;
    e.b = (float4)(0.0f);
    e.c = t * cos(delta);
    e.d = t * sin(delta);
    return e;
}

/* A unit vector normal to k: `x`'s part normal to k, or any such vector when x has none. */
inline float3 stokes_basis_from(float3 k, float3 x)
{
    float3 t = x - k * dot(k, x);
    float n = length(t);
    if (n > 1.0e-6f && isfinite(n)) return t / n;
    float3 u, v;
    orthonormal_basis(k, &u, &v);
    return u;
}

#endif

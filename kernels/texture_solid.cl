/* Solid textures: values defined throughout space and looked up at the surface point itself rather than at its
 * (u, v), as pbrt-v4 defines them (Pharr, Jakob & Humphreys, 4th ed., 10.6.2 "Random Polka Dots" for the 3D
 * mapping, 10.6.3 "Noise Idioms and Spectral Synthesis": fractional Brownian motion and turbulence, "Windy Waves",
 * 10.6.5 "Marble"), on kernels/noise.cl's Perlin noise.
 *
 * Contract: a solid texture's row (Texture) points with data_offset at TEXTURE_SOLID_FLOATS floats of the texel
 * buffer (host/spectrace/textures/solid.py writes them): the 3 × 4 matrix (rows) that takes the world-space point
 * into texture space (the inverse of the texture's placement, marble's scale folded in), the octave count, ω (the
 * `roughness`: each octave's weight is ω times the one before), marble's variation, and for marble the spectrum
 * table offsets (as int bits) of its nine spline colours. Unitless values: fbm, windy about [−2, 2], wrinkled
 * [0, 2], marble a reflectance in [0.3, 0.9].
 *
 * The octaves are all summed, unfiltered: pbrt-v4 fades the finest octaves out where the lookup's footprint is
 * wider than their wavelength, which its value at a point without a footprint (ray differentials of 0) equals. */
#ifndef SPECTRACE_TEXTURE_SOLID_CL
#define SPECTRACE_TEXTURE_SOLID_CL

#include "noise.cl"

#define TEXTURE_SOLID_FLOATS 28
#define SOLID_OCTAVES 12
#define SOLID_OMEGA 13
#define SOLID_VARIATION 14
#define SOLID_MARBLE_COLOURS 16
/* Each octave's frequency is 1.99 times the one before (pbrt-v4's lacunarity: just under 2, so that the octaves'
 * lattices do not line up). */
#define SOLID_LACUNARITY 1.99f

inline int texture_is_solid(__global const Texture *t)
{
    return t->type == TEXTURE_FBM || t->type == TEXTURE_WRINKLED || t->type == TEXTURE_WINDY
        || t->type == TEXTURE_MARBLE;
}

/* Σ_{i<octaves} ω^i noise(1.99^i p): fractional Brownian motion. */
inline float solid_fbm(float3 p, float omega, int octaves)
{
    float sum = 0.0f, frequency = 1.0f, weight = 1.0f;
    for (int i = 0; i < octaves; ++i) {
        sum += weight * perlin_noise(frequency * p);
        frequency *= SOLID_LACUNARITY;
        weight *= omega;
    }
    return sum;
}

/* Σ_{i<octaves} ω^i |noise(1.99^i p)| + 0.2 ω^octaves: turbulence, its octaves beyond the last counted at 0.2, the
 * mean of |noise| pbrt-v4 puts for the octaves a filter drops (with none dropped, the one term after the last). */
inline float solid_turbulence(float3 p, float omega, int octaves)
{
    float sum = 0.0f, frequency = 1.0f, weight = 1.0f;
    for (int i = 0; i < octaves; ++i) {
        sum += weight * fabs(perlin_noise(frequency * p));
        frequency *= SOLID_LACUNARITY;
        weight *= omega;
    }
    return sum + 0.2f * weight;
}

/* Marble: the nine colours' cubic Bézier segments (de Casteljau) at t = ½ + ½ sin(y + variation · fbm(p)); the
 * segments overlap, six of them over t in [0, 1]. Blends the colours' spectra (each already 1.5 × the book's RGB,
 * uplifted on the host), where pbrt-v4 blends RGB and uplifts the blend. */
inline float4 solid_marble(const TextureBuffers *b, __global const float *q, float3 p, const SampledWavelengths *w)
{
    float marble = p.y + q[SOLID_VARIATION] * solid_fbm(p, q[SOLID_OMEGA], (int)q[SOLID_OCTAVES]);
    float t = 0.5f + 0.5f * sin(marble);
    const int segments = 6;
    int first = clamp((int)floor(t * segments), 0, segments - 1);
    t = t * segments - (float)first;
    __global const int *colours = (__global const int *)(q + SOLID_MARBLE_COLOURS) + first;
    float4 c0 = spectrum_at(b->spectra, colours[0], w), c1 = spectrum_at(b->spectra, colours[1], w);
    float4 c2 = spectrum_at(b->spectra, colours[2], w), c3 = spectrum_at(b->spectra, colours[3], w);
    float4 s0 = mix(c0, c1, t), s1 = mix(c1, c2, t), s2 = mix(c2, c3, t);
    s0 = mix(s0, s1, t);
    s1 = mix(s1, s2, t);
    return mix(s0, s1, t);
}

/* Solid texture t at the world-space point p, at the path's wavelengths (the noise textures are the same at all). */
inline float4 solid_texture_spectrum(const TextureBuffers *b, __global const Texture *t, float3 p,
                                     const SampledWavelengths *w)
{
    __global const float *q = b->texels + t->data_offset;
    float4 h = (float4)(p, 1.0f);
    float3 x = (float3)(dot(vload4(0, q), h), dot(vload4(1, q), h), dot(vload4(2, q), h));
    float omega = q[SOLID_OMEGA];
    int octaves = (int)q[SOLID_OCTAVES];
    if (t->type == TEXTURE_FBM) return (float4)(solid_fbm(x, omega, octaves));
    if (t->type == TEXTURE_WRINKLED) return (float4)(solid_turbulence(x, omega, octaves));
    if (t->type == TEXTURE_WINDY) {
        /* pbrt-v4's windy waves: the wind's strength a slow fbm (a tenth of the frequency, 3 octaves), the waves'
         * height a 6-octave fbm, both of ω ½. */
        return (float4)(fabs(solid_fbm(0.1f * x, 0.5f, 3)) * solid_fbm(x, 0.5f, 6));
    }
    return solid_marble(b, q, x, w);
}

#endif

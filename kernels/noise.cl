/* Perlin noise (Perlin 2002, "Improving Noise", SIGGRAPH: the quintic fade 6t⁵ − 15t⁴ + 10t³ and gradients drawn
 * from the twelve cube-edge directions by a hashed 4-bit code), as pbrt-v4 describes it (Pharr, Jakob & Humphreys,
 * 4th ed., 10.6.1 "Perlin Noise": lattice points hashed through Perlin's permutation of 0..255, their coordinates
 * wrapped to 256; a 2D lookup is the 3D one at z = ½), and the procedural textures built on it (10.6.4 "Polka
 * Dots"). Unitless: noise takes a point in lattice units and returns a value in about [−1, 1], 0 at every lattice
 * point. */
#ifndef SPECTRACE_NOISE_CL
#define SPECTRACE_NOISE_CL

/* Ken Perlin's permutation of 0..255 (the reference implementation's table), which pbrt-v4's noise uses too: the
 * same table gives the same dots as pbrt-v4 at the same st. */
__constant uchar NOISE_PERMUTATION[256] = {
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30,
    69, 142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62,
    94, 252, 219, 203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136,
    171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122,
    60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161,
    1, 216, 80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86,
    164, 100, 109, 198, 173, 186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126,
    255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213,
    119, 248, 152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253,
    19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193,
    238, 210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31,
    181, 199, 106, 157, 184, 84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93,
    222, 114, 67, 29, 24, 72, 243, 141, 128, 195, 78, 66, 215, 61, 156, 180};

inline int noise_hash(int x, int y, int z)
{
    int a = NOISE_PERMUTATION[x & 255];
    int b = NOISE_PERMUTATION[(a + y) & 255];
    return NOISE_PERMUTATION[(b + z) & 255];
}

/* The gradient of lattice point (x, y, z) dotted with the offset d from it: Perlin's 12 edge directions (and 4
 * repeats, to fill 16 codes) as sums of two signed offset components. */
inline float noise_gradient(int x, int y, int z, float3 d)
{
    int h = noise_hash(x, y, z) & 15;
    float u = (h < 8 || h == 12 || h == 13) ? d.x : d.y;
    float v = (h < 4 || h == 12 || h == 13) ? d.y : d.z;
    return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

inline float noise_fade(float t)
{
    return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f);
}

/* Perlin noise at p: the eight surrounding lattice points' gradient ramps blended by the fade of p's offsets. */
inline float perlin_noise(float3 p)
{
    float3 cell = floor(p);
    float3 d = p - cell;
    int x = (int)cell.x, y = (int)cell.y, z = (int)cell.z;
    float3 f = (float3)(noise_fade(d.x), noise_fade(d.y), noise_fade(d.z));
    float x00 = mix(noise_gradient(x, y, z, d), noise_gradient(x + 1, y, z, d - (float3)(1.0f, 0.0f, 0.0f)), f.x);
    float x10 = mix(noise_gradient(x, y + 1, z, d - (float3)(0.0f, 1.0f, 0.0f)),
                    noise_gradient(x + 1, y + 1, z, d - (float3)(1.0f, 1.0f, 0.0f)), f.x);
    float x01 = mix(noise_gradient(x, y, z + 1, d - (float3)(0.0f, 0.0f, 1.0f)),
                    noise_gradient(x + 1, y, z + 1, d - (float3)(1.0f, 0.0f, 1.0f)), f.x);
    float x11 = mix(noise_gradient(x, y + 1, z + 1, d - (float3)(0.0f, 1.0f, 1.0f)),
                    noise_gradient(x + 1, y + 1, z + 1, d - (float3)(1.0f)), f.x);
    return mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z);
}

/* 2D noise: the 3D noise on the plane z = ½ (a lattice plane would give 0 along every lattice line). */
inline float perlin_noise2(float x, float y)
{
    return perlin_noise((float3)(x, y, 0.5f));
}

/* Which side of a polka-dot texture st is on (0: on a dot). Cells of unit size are centred on the integer points;
 * the noise at the cell's centre + ½ says whether it has a dot, the noise at two more of its points shift the dot's
 * centre by up to 0.15 in s and t, so that a dot of radius 0.35 stays inside its cell. */
#define DOTS_RADIUS 0.35f
#define DOTS_MAX_SHIFT 0.15f

inline int dots_side(float2 st)
{
    float2 cell = floor(st + 0.5f);
    if (!(perlin_noise2(cell.x + 0.5f, cell.y + 0.5f) > 0.0f)) return 1;
    float2 centre = cell + DOTS_MAX_SHIFT * (float2)(perlin_noise2(cell.x + 1.5f, cell.y + 2.8f),
                                                     perlin_noise2(cell.x + 4.5f, cell.y + 9.8f));
    float2 offset = st - centre;
    return !(dot(offset, offset) < DOTS_RADIUS * DOTS_RADIUS);
}

#endif

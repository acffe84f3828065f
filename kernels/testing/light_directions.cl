/* Test harness: the directions light paths leave a delta-position light in (point, spot, projector, goniometric),
 * as BDPT draws them (bdpt.cl: light_<type>_sample_direction) and the density it gives them
 * (light_<type>_pdf_direction), for the scene's light 0:
 * - light_direction_samples: the direction drawn from each u and its density there;
 * - light_direction_pdfs: the density at given unit directions.
 * Built without scene-feature defines, so one program serves every light type (kernels/scene_features.h). */
#include "kernel_entry.h"
#include "path_state.cl"
#include "light_emission.cl"

inline float3 harness_sample_direction(__global const Light *light, __global const float4 *texels, float2 u)
{
#define X(name, NAME) if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_sample_direction(light, texels, u);
    LIGHT_LIST_POSITION(X)
#undef X
    return (float3)(0.0f);
}

inline float harness_pdf_direction(__global const Light *light, __global const float4 *texels, float3 d)
{
#define X(name, NAME) if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_pdf_direction(light, texels, d);
    LIGHT_LIST_POSITION(X)
#undef X
    return 0.0f;
}

/* direction_pdf: (unit direction, its density per steradian). */
KERNEL void light_direction_samples(SCENE_KERNEL_PARAMS, __global const float2 *u, __global float4 *direction_pdf,
                                    int count)
{
    int i = get_global_id(0);
    if (i >= count) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    float3 d = harness_sample_direction(&scene.lights[0], scene.texels, u[i]);
    direction_pdf[i] = (float4)(d, harness_pdf_direction(&scene.lights[0], scene.texels, d));
}

KERNEL void light_direction_pdfs(SCENE_KERNEL_PARAMS, __global const float4 *directions, __global float *pdf,
                                 int count)
{
    int i = get_global_id(0);
    if (i >= count) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    pdf[i] = harness_pdf_direction(&scene.lights[0], scene.texels, directions[i].xyz);
}

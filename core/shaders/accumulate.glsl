// Progressive accumulation (kit.h): the running average of the frames of a
// still view, restarted by the kit (u_frame = 0) on any change. Writes the
// average to the accumulation image and to the method's target.
#ifndef GI_ACCUMULATE_GLSL
#define GI_ACCUMULATE_GLSL
#include "glsl_shared.h"
#include "view.glsl"

layout(rgba32f, binding = GI_IMAGE_ACCUM) uniform image2D gi_accum_image;
layout(rgba32f, binding = GI_IMAGE_TARGET) uniform writeonly image2D gi_target_image;

// Adds this frame's estimate L at px; returns the new average.
vec3 gi_accumulate_store(ivec2 px, vec3 L)
{
    vec3 avg = L;
    if (u_frame > 0u) {
        vec3 prev = imageLoad(gi_accum_image, px).rgb;
        avg = prev + (L - prev) / float(u_frame + 1u);
    }
    imageStore(gi_accum_image, px, vec4(avg, 1.0));
    imageStore(gi_target_image, px, vec4(avg, 1.0));
    return avg;
}
#endif

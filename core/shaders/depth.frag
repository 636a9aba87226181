// Depth-map pass, fragment stage: depth peeling. Pass k keeps the nearest
// surface strictly behind the one pass k-1 kept at this texel and writes its
// linear depth into channel k of the map (colour mask) and into u_prev's
// successor for the next pass.
in vec3 v_eye;
flat in uint v_cull; // depth.vert: 0 both sides, 1 cull back faces, 2 cull front (mirrored)

uniform int u_metric;   // 0 eye z, 1 radial
uniform int u_peel;     // 0 for the first surface
uniform sampler2D u_prev;
uniform int u_receiver_side; // gi_depth_desc.receiver_side (2: both sides drawn)

layout(location = 0) out vec4 o_depth;  // the map layer, one channel unmasked
layout(location = 1) out float o_next;  // this pass's depth, read by the next

void main()
{
    // The one rule for sides (gi/scene.h): a single-sided back face is no
    // surface, so it casts no shadow and hides nothing. Seen from the eye,
    // or with u_receiver_side from the receivers behind the map's surfaces
    // (a shadow ray cast toward the eye meets the face the eye sees from
    // behind).
    // Mode 3: the first surface by the eye's rule, the later ones of both
    // sides, so a closed object's exit (a back face from the eye) follows
    // its entry and the pair is a closed interval.
    bool front = gl_FrontFacing != (v_cull == 2u);
    bool both = u_receiver_side == 2 || (u_receiver_side == 3 && u_peel > 0);
    if (v_cull != 0u && !both && front == (u_receiver_side == 1))
        discard;
    float d = u_metric == 1 ? length(v_eye) : -v_eye.z;
    if (u_peel > 0) {
        float prev = texelFetch(u_prev, ivec2(gl_FragCoord.xy), 0).r;
        if (d <= prev * (1.0 + 1e-6) + 1e-7)
            discard;
    }
    o_depth = vec4(d);
    o_next = d;
}

// Depth-map pass, fragment stage: depth peeling. Pass k keeps the nearest
// surface strictly behind the one pass k-1 kept at this texel and writes its
// linear depth into channel k of the map (colour mask) and into u_prev's
// successor for the next pass.
in vec3 v_eye;
flat in uint v_cull; // depth.vert: 0 both sides, 1 cull back faces, 2 cull front (mirrored)

uniform int u_metric;   // 0 eye z, 1 radial
uniform int u_peel;     // 0 for the first surface
uniform sampler2D u_prev;
uniform int u_receiver_side; // gi_depth_desc.receiver_side, a gi_sides (gi/passes.h)

// gi_sides (gi/passes.h): the same numbers
const int SIDES_EYE = 0;
const int SIDES_RECEIVERS = 1;
const int SIDES_BOTH = 2;
const int SIDES_EYE_THEN_BOTH = 3;
const int SIDES_RECEIVERS_THEN_BOTH = 4;
const int SIDES_ANY_THEN_RECEIVERS = 5;

layout(location = 0) out vec4 o_depth;  // the map layer, one channel unmasked
layout(location = 1) out float o_next;  // this pass's depth, read by the next

void main()
{
    // The one rule for sides (gi/scene.h): a single-sided back face is no
    // surface, so it casts no shadow and hides nothing. Seen from the eye,
    // or with SIDES_RECEIVERS from the receivers behind the map's surfaces
    // (a shadow ray cast toward the eye meets the face the eye sees from
    // behind).
    // EYE_THEN_BOTH: the first surface by the eye's rule, the later ones of
    // both sides, so a closed object's exit (a back face from the eye)
    // follows its entry and the pair is a closed interval.
    // RECEIVERS_THEN_BOTH: the same with the first surface by the
    // receivers' rule.
    // ANY_THEN_RECEIVERS: the first surface of either side; the second, when
    // the first is no surface for the receivers, the first one behind it
    // that is (else of either side): a closed object's entry and exit, a
    // face the eye sees from behind and what follows it.
    bool front = gl_FrontFacing != (v_cull == 2u);
    bool receivers_see = v_cull == 0u || !front; // a surface for rays cast toward the eye
    float raw_prev = u_peel > 0 ? texelFetch(u_prev, ivec2(gl_FragCoord.xy), 0).r : 0.0;
    float prev = abs(raw_prev);
    bool keep;
    if (u_receiver_side == SIDES_ANY_THEN_RECEIVERS)
        keep = u_peel != 1 || raw_prev < 0.0 || receivers_see;
    else if (u_receiver_side == SIDES_BOTH || (u_receiver_side >= SIDES_EYE_THEN_BOTH && u_peel > 0))
        keep = true;
    else if (u_receiver_side == SIDES_RECEIVERS || u_receiver_side == SIDES_RECEIVERS_THEN_BOTH)
        keep = receivers_see;
    else
        keep = v_cull == 0u || front;
    if (!keep)
        discard;
    float d = u_metric == 1 ? length(v_eye) : -v_eye.z;
    if (u_peel > 0 && d <= prev * (1.0 + 1e-6) + 1e-7)
        discard;
    // ANY_THEN_RECEIVERS marks its first surface by the sign (depths are
    // positive): for the next pass one the receivers see, in the map one
    // they do not (gi_sides)
    bool mark = u_receiver_side == SIDES_ANY_THEN_RECEIVERS && u_peel == 0;
    o_depth = vec4(mark && !receivers_see ? -d : d);
    o_next = mark && receivers_see ? -d : d;
}

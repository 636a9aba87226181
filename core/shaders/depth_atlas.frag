// Depth atlas, fragment stage: the linear depth of the nearest surface
// (the depth test keeps it) as colour, in the atlas' metric.
uniform int u_metric; // 0 eye z, 1 radial
uniform int u_receiver_side; // gi_depth_atlas_desc.receiver_side, a gi_sides (gi/passes.h)

const int SIDES_RECEIVERS = 1; // GI_SIDES_RECEIVERS; 0 is GI_SIDES_EYE

in vec3 v_eye;
flat in uint v_single; // 1: single-sided material, its back faces are no surface (gi/scene.h)

layout(location = 0) out float o_depth;

void main()
{
    // EYE: a face the eye sees from behind is no surface; RECEIVERS: one
    // the receivers (behind the map's surfaces) see from behind is none
    if (v_single != 0u && gl_FrontFacing == (u_receiver_side == SIDES_RECEIVERS))
        discard;
    o_depth = u_metric == 1 ? length(v_eye) : -v_eye.z;
}

// Direction parameterisation, map basis and projection of the csm plugin:
// the GLSL twin of plugins/csm/csm_cpu.c (see csm_cpu.h for the formulas);
// plugins/csm/tests/csm_twins.c holds the two equal.
#ifndef CSM_GEOM_GLSL
#define CSM_GEOM_GLSL

#define CSM_EYE 2.0
#define CSM_PI 3.14159265358979323846
#define CSM_INV_PI 0.31830988618379067154

// (theta, phi) of the centre of cell (a, b).
vec2 csm_cell_angles(uint n_theta, uint n_phi, uint a, uint b)
{
    return vec2(CSM_PI * (float(b) + 0.5) / float(n_theta), 2.0 * CSM_PI * (float(a) + 0.5) / float(n_phi));
}

vec3 csm_dir(float theta, float phi)
{
    float st = sin(theta);
    return vec3(st * cos(phi), cos(theta), st * sin(phi));
}

// Continuous grid coordinates (u along phi, v along theta) of unit w.
vec2 csm_grid_coords(vec3 w, uint n_theta, uint n_phi)
{
    float theta = atan(sqrt(w.x * w.x + w.z * w.z), w.y);
    float phi = (w.x == 0.0 && w.z == 0.0) ? 0.0 : atan(w.z, w.x);
    if (phi < 0.0)
        phi += 2.0 * CSM_PI;
    return vec2(phi * (0.5 * CSM_INV_PI) * float(n_phi) - 0.5, theta * CSM_INV_PI * float(n_theta) - 0.5);
}

void csm_basis(float theta, float phi, out vec3 t, out vec3 b, out vec3 d)
{
    d = csm_dir(theta, phi);
    t = vec3(-sin(phi), 0.0, cos(phi));
    b = cross(d, t);
}

// (sx, sy, depth) of local point x in the map of (theta, phi); sphere = (c, R).
vec3 csm_project(vec4 sphere, float theta, float phi, vec3 x)
{
    vec3 t, b, d;
    csm_basis(theta, phi, t, b, d);
    vec3 p = x - sphere.xyz;
    return vec3(dot(p, t) / sphere.w, dot(p, b) / sphere.w, CSM_EYE * sphere.w - dot(p, d));
}

#endif

/* Isotropic re-meshing and point location by CGAL (gi/algo/remesh.h): the one
 * file that includes CGAL. Exceptions never cross the C boundary. */
#include "gi/algo/remesh.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/detect_features.h>
#include <CGAL/Surface_mesh.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <vector>

namespace
{

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Mesh;
namespace PMP = CGAL::Polygon_mesh_processing;

typedef std::vector<K::Triangle_3>::const_iterator TriIter;
typedef CGAL::AABB_triangle_primitive<K, TriIter> Primitive;
typedef CGAL::AABB_traits<K, Primitive> Traits;
typedef CGAL::AABB_tree<Traits> Tree;

/* The input's non-degenerate triangles in an AABB tree, with the input
 * index of each. */
struct Locator {
    std::vector<K::Triangle_3> tris;
    std::vector<uint32_t> ids;
    Tree tree;

    Locator(const float *p, const uint32_t *ix, uint32_t nt)
    {
        for (uint32_t t = 0; t < nt; t++) {
            const float *a = &p[3 * (size_t)ix[3 * t]], *b = &p[3 * (size_t)ix[3 * t + 1]],
                        *c = &p[3 * (size_t)ix[3 * t + 2]];
            K::Triangle_3 tr(Point(a[0], a[1], a[2]), Point(b[0], b[1], b[2]),
                             Point(c[0], c[1], c[2]));
            if (tr.is_degenerate())
                continue;
            tris.push_back(tr);
            ids.push_back(t);
        }
        tree.insert(tris.begin(), tris.end());
        tree.accelerate_distance_queries();
    }

    /* Nearest point on the input: its triangle and barycentric weights. */
    void locate(double x, double y, double z, uint32_t *face, float w[3]) const
    {
        Point q(x, y, z);
        auto hit = tree.closest_point_and_primitive(q);
        size_t k = (size_t)(hit.second - tris.begin());
        const K::Triangle_3 &tr = tris[k];
        *face = ids[k];
        /* barycentric weights of the closest point (in the triangle's plane) */
        K::Vector_3 v0 = tr[1] - tr[0], v1 = tr[2] - tr[0], v2 = hit.first - tr[0];
        double d00 = v0 * v0, d01 = v0 * v1, d11 = v1 * v1, d20 = v2 * v0, d21 = v2 * v1;
        double den = d00 * d11 - d01 * d01;
        double b1 = den != 0.0 ? (d11 * d20 - d01 * d21) / den : 1.0 / 3.0;
        double b2 = den != 0.0 ? (d00 * d21 - d01 * d20) / den : 1.0 / 3.0;
        b1 = b1 < 0.0 ? 0.0 : (b1 > 1.0 ? 1.0 : b1);
        b2 = b2 < 0.0 ? 0.0 : (b2 > 1.0 ? 1.0 : b2);
        if (b1 + b2 > 1.0) {
            double s = b1 + b2;
            b1 /= s;
            b2 /= s;
        }
        double b0 = 1.0 - b1 - b2;
        w[0] = (float)(b0 > 0.0 ? b0 : 0.0);
        w[1] = (float)b1;
        w[2] = (float)b2;
    }
};

bool check_input(const float *positions, uint32_t nv, const uint32_t *indices, uint32_t nt,
                 const char *what, gi_error *err)
{
    if (!positions || !indices || nv == 0 || nt == 0) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: the mesh has no triangles", what);
        return false;
    }
    for (size_t i = 0; i < (size_t)nt * 3; i++)
        if (indices[i] >= nv) {
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                         "%s: index %u of triangle %zu is out of range (%u vertices)", what,
                         indices[i], i / 3, nv);
            return false;
        }
    for (size_t i = 0; i < (size_t)nv * 3; i++)
        if (!std::isfinite(positions[i])) {
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: vertex %zu is not finite", what, i / 3);
            return false;
        }
    return true;
}

/* The input as a polygon soup without its degenerate triangles (points
 * are not merged: a caller's split vertices stay split), oriented
 * (non-manifold vertices cut apart), then a halfedge mesh. false when
 * every triangle is degenerate. */
bool soup_to_mesh(const float *positions, uint32_t vertex_count, const uint32_t *indices,
                  uint32_t triangle_count, Mesh &mesh)
{
    std::vector<Point> pts;
    pts.reserve(vertex_count);
    for (uint32_t v = 0; v < vertex_count; v++)
        pts.emplace_back(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
    std::vector<std::vector<std::size_t>> polys;
    polys.reserve(triangle_count);
    for (uint32_t t = 0; t < triangle_count; t++) {
        uint32_t a = indices[3 * t], b = indices[3 * t + 1], c = indices[3 * t + 2];
        if (a == b || b == c || a == c || CGAL::collinear(pts[a], pts[b], pts[c]))
            continue;
        polys.push_back({a, b, c});
    }
    if (polys.empty())
        return false;
    PMP::orient_polygon_soup(pts, polys);
    PMP::polygon_soup_to_polygon_mesh(pts, polys, mesh);
    return true;
}

/* CGAL's isotropic re-meshing of the whole mesh toward target_edge, its
 * borders and sharp creases kept. */
void remesh_features_kept(Mesh &mesh, double target_edge, uint32_t iterations)
{
    /* the input's border vertices stay (a border's corners with them):
     * the border keeps its shape and the surface its area */
    auto fixed = mesh.add_property_map<Mesh::Vertex_index, bool>("v:gi_fixed", false).first;
    for (Mesh::Halfedge_index h : mesh.halfedges())
        if (mesh.is_border(h))
            fixed[mesh.target(h)] = true;
    /* creases sharper than 60 degrees inside a patch: their edges are
     * split but not flipped, their vertices stay */
    auto sharp = mesh.add_property_map<Mesh::Edge_index, bool>("e:gi_sharp", false).first;
    PMP::detect_sharp_edges(mesh, 60.0, sharp);
    for (Mesh::Edge_index e : mesh.edges())
        if (sharp[e]) {
            fixed[mesh.vertex(e, 0)] = true;
            fixed[mesh.vertex(e, 1)] = true;
        }
    PMP::isotropic_remeshing(faces(mesh), target_edge, mesh,
                             CGAL::parameters::number_of_iterations(iterations)
                                 .vertex_is_constrained_map(fixed)
                                 .edge_is_constrained_map(sharp));
}

/* The re-meshed surface into r: compact vertex numbering, then each
 * vertex located on the input (its triangle and barycentric weights).
 * false, with err set, when out of memory or a face is no triangle. */
bool copy_remeshed(const Mesh &mesh, const float *positions, const uint32_t *indices,
                   uint32_t triangle_count, gi_remeshed *r, gi_error *err)
{
    std::vector<uint32_t> id(mesh.number_of_vertices() + mesh.number_of_removed_vertices(),
                             UINT32_MAX);
    uint32_t nv = 0;
    for (Mesh::Vertex_index v : mesh.vertices())
        id[(size_t)v] = nv++;
    uint32_t nf = (uint32_t)mesh.number_of_faces();
    r->vertex_count = nv;
    r->triangle_count = nf;
    r->positions = (float *)malloc(((size_t)nv * 3 + 1) * sizeof(float));
    r->face = (uint32_t *)malloc(((size_t)nv + 1) * sizeof(uint32_t));
    r->bary = (float *)malloc(((size_t)nv * 3 + 1) * sizeof(float));
    r->indices = (uint32_t *)malloc(((size_t)nf * 3 + 1) * sizeof(uint32_t));
    if (!r->positions || !r->face || !r->bary || !r->indices) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "remesh: out of memory for %u vertices", nv);
        return false;
    }
    Locator loc(positions, indices, triangle_count);
    for (Mesh::Vertex_index v : mesh.vertices()) {
        uint32_t i = id[(size_t)v];
        const Point &p = mesh.point(v);
        r->positions[3 * i] = (float)p.x();
        r->positions[3 * i + 1] = (float)p.y();
        r->positions[3 * i + 2] = (float)p.z();
        loc.locate(p.x(), p.y(), p.z(), &r->face[i], &r->bary[3 * i]);
    }
    uint32_t f = 0;
    for (Mesh::Face_index fi : mesh.faces()) {
        int c = 0;
        for (Mesh::Vertex_index v : vertices_around_face(mesh.halfedge(fi), mesh))
            if (c < 3)
                r->indices[3 * f + c++] = id[(size_t)v];
        if (c != 3) {
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                         "remesh: CGAL returned a face with %d corners", c);
            return false;
        }
        f++;
    }
    return true;
}

} // namespace

extern "C" gi_remeshed *gi_remesh_isotropic(const float *positions, uint32_t vertex_count,
                                            const uint32_t *indices, uint32_t triangle_count,
                                            float target_edge, uint32_t iterations, gi_error *err)
{
    if (!check_input(positions, vertex_count, indices, triangle_count, "remesh", err))
        return NULL;
    if (!(target_edge > 0.0f) || !std::isfinite(target_edge) || iterations == 0 ||
        iterations > 100) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                     "remesh: target edge %g must be > 0 and iterations %u in 1..100",
                     (double)target_edge, iterations);
        return NULL;
    }
    gi_remeshed *r = (gi_remeshed *)calloc(1, sizeof *r);
    if (!r) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "remesh: out of memory");
        return NULL;
    }
    try {
        Mesh mesh;
        if (!soup_to_mesh(positions, vertex_count, indices, triangle_count, mesh)) {
            gi_remeshed_free(r);
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "remesh: every triangle is degenerate");
            return NULL;
        }
        remesh_features_kept(mesh, (double)target_edge, iterations);
        if (!copy_remeshed(mesh, positions, indices, triangle_count, r, err)) {
            gi_remeshed_free(r);
            return NULL;
        }
        return r;
    } catch (const std::exception &e) {
        gi_remeshed_free(r);
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "remesh: CGAL failed: %s", e.what());
        return NULL;
    } catch (...) {
        gi_remeshed_free(r);
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "remesh: CGAL failed");
        return NULL;
    }
}

extern "C" void gi_remeshed_free(gi_remeshed *r)
{
    if (!r)
        return;
    free(r->positions);
    free(r->face);
    free(r->bary);
    free(r->indices);
    free(r);
}

extern "C" gi_result gi_mesh_locate(const float *positions, uint32_t vertex_count,
                                    const uint32_t *indices, uint32_t triangle_count,
                                    const float *points, uint32_t count, uint32_t *face,
                                    float *bary, gi_error *err)
{
    if (!check_input(positions, vertex_count, indices, triangle_count, "locate", err))
        return GI_ERR_INVALID_ARGUMENT;
    try {
        Locator loc(positions, indices, triangle_count);
        if (loc.tris.empty())
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "locate: every triangle is degenerate");
        for (uint32_t i = 0; i < count; i++)
            loc.locate(points[3 * i], points[3 * i + 1], points[3 * i + 2], &face[i], &bary[3 * i]);
        return GI_OK;
    } catch (const std::exception &e) {
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "locate: CGAL failed: %s", e.what());
    } catch (...) {
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "locate: CGAL failed");
    }
}

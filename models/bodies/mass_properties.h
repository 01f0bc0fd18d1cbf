// Mass properties of a solid bounded by a closed triangle surface
// (docs/physics.md "Rigid bodies (affine bodies)"): volume, mass, centre of
// mass and the principal frame, from surface integrals alone by the
// divergence theorem, after D. Eberly, "Polyhedral Mass Properties
// (Revisited)", Geometric Tools, 2002 (the same integrals as B. Mirtich,
// "Fast and Accurate Computation of Polyhedral Mass Properties", J. Graphics
// Tools 1(2), 1996, specialised to triangles). Each outward-oriented
// triangle contributes closed-form polynomials of its vertices to the
// integrals of 1, x, y, z, x^2, y^2, z^2, xy, yz, zx over the solid.
//
// The affine body (bodies.h) needs the second moments about the centre,
// C = integral rho (x - c)(x - c)^T dV, in the frame where C is diagonal:
// its diagonal J_i = integral rho X_i^2 dV is the mass of the column a_i.
// (The inertia tensor is I = tr(C) 1 - C, so I_1 = J_2 + J_3, ...)
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace springlab {

// A triangle of a body's closed surface: its three vertices' indices,
// counter-clockwise seen from outside (models/fem/fem.h's Triangle is an
// element).
using SurfaceTriangle = std::array<int, 3>;

struct MassProperties {
  double volume = 0.0;                                  // V [m^3]
  double mass = 0.0;                                    // m = rho V [kg]
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();     // c [m]
  // C = integral rho (x - c)(x - c)^T dV [kg m^2], in the mesh's frame.
  Eigen::Matrix3d second_moment = Eigen::Matrix3d::Zero();
  // The principal frame: R (a rotation, det +1) with R^T C R = diag(J).
  // Columns ordered and signed to be nearest the mesh's own axes, so a
  // mesh already in its principal frame has R = I (see principal_frame).
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();
  Eigen::Vector3d J = Eigen::Vector3d::Zero();          // J_i [kg m^2]
};

// The integrals of the solid bounded by `triangles` (counter-clockwise seen
// from outside), density rho. The surface must be closed (surface_problem);
// integrals are taken about the vertices' mean, so a body far from the
// origin loses no digits to cancellation.
MassProperties mass_properties(const std::vector<Eigen::Vector3d>& vertices,
                               const std::vector<SurfaceTriangle>& triangles, double density);

// R and J of a symmetric second moment C: eigenvectors, then the column
// permutation and signs that maximise trace(R) with det R = +1.
void principal_frame(const Eigen::Matrix3d& C, Eigen::Matrix3d& R, Eigen::Vector3d& J);

// Why `triangles` do not bound a solid, or empty: an index out of range or
// repeated within a triangle, a triangle of zero area (below 1e-12 of its
// longest edge squared), an edge not shared by exactly two triangles of
// opposite orientation (an open or non-manifold surface, or inconsistent
// orientation), a volume of zero (below 1e-12 of the bounding box's
// diameter cubed) or negative (triangles clockwise seen from outside).
std::string surface_problem(const std::vector<Eigen::Vector3d>& vertices,
                            const std::vector<SurfaceTriangle>& triangles);

// Closed surfaces of the built-in shapes, centred at the origin, outward
// oriented: a box of side lengths `size` along x, y, z (8 vertices, 12
// triangles), and a cylinder of `radius` and `height` about the z axis,
// a prism over the regular `segments`-gon inscribed in the circle (the
// vertices on the circle; 2 segments + 2 vertices).
void box_surface(const Eigen::Vector3d& size, std::vector<Eigen::Vector3d>& vertices,
                 std::vector<SurfaceTriangle>& triangles);
void cylinder_surface(double radius, double height, int segments,
                      std::vector<Eigen::Vector3d>& vertices,
                      std::vector<SurfaceTriangle>& triangles);

}  // namespace springlab

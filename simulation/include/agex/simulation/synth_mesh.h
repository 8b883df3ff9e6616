#pragma once
// A triangle mesh that the synthetic renderer can ray cast: a bounding volume
// hierarchy (median splits, up to 4 triangles per leaf) over its triangles.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

namespace agex
{
class SynthMesh
{
public:
  /** \brief Builds the hierarchy. Triangles index vertices; degenerate triangles are
    * kept but never hit. \throws std::invalid_argument for an index out of range */
  SynthMesh (std::vector<Eigen::Vector3d> vertices, std::vector<Eigen::Vector3i> triangles);

  const std::vector<Eigen::Vector3d> &vertices () const { return vertices_; }
  const std::vector<Eigen::Vector3i> &triangles () const { return triangles_; }

  /** \brief Nearest hit at t > t_min along origin + t * direction; sets the unit
    * normal of the triangle hit, turned towards the ray's origin, and the index of that
    * triangle (into triangles()). -1 if none (normal and triangle left as they are). */
  double intersect (const Eigen::Vector3d &origin, const Eigen::Vector3d &direction, double t_min,
                    Eigen::Vector3d *normal, int *triangle = nullptr) const;

  /** Unsigned distance from p to the nearest triangle (+inf for an empty mesh). */
  double distance (const Eigen::Vector3d &p) const;

  /** A sphere around every vertex (radius 0 for an empty mesh). */
  const Eigen::Vector3d &sphereCentre () const { return sphere_centre_; }
  double sphereRadius () const { return sphere_radius_; }

private:
  struct Node
  {
    Eigen::AlignedBox3d box;
    int first = 0;   ///< leaf: first entry in order_; inner: index of the right child
    int count = 0;   ///< triangles in a leaf, 0 for an inner node (left child = this + 1)
  };
  int build (int begin, int end, std::vector<Eigen::Vector3d> &centroids);

  std::vector<Eigen::Vector3d> vertices_;
  std::vector<Eigen::Vector3i> triangles_;
  std::vector<Node> nodes_;
  std::vector<int> order_;
  Eigen::Vector3d sphere_centre_ = Eigen::Vector3d::Zero ();
  double sphere_radius_ = 0.0;
};
}  // namespace agex

#include <agex/simulation/synth_mesh.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace agex
{
namespace
{
constexpr int kLeafSize = 4;
constexpr double kInf = std::numeric_limits<double>::infinity ();
/** How far (in barycentric units) a triangle reaches beyond its edges: a ray through a vertex
  * or an edge that triangles share must not slip between them by rounding (a frame meshed
  * through its pixel centres is hit by rays through its vertices: FrameReprojection). */
constexpr double kEdgeSlack = 1e-9;

/** Entry and exit of a ray (inverse direction given) through a box; false if missed. */
bool
slab (const Eigen::AlignedBox3d &box, const Eigen::Vector3d &o, const Eigen::Vector3d &inv, double t_max, double &t_enter)
{
  double t0 = 0.0, t1 = t_max;
  for (int a = 0; a < 3; ++a)
  {
    double near = (box.min ()[a] - o[a]) * inv[a], far = (box.max ()[a] - o[a]) * inv[a];
    if (near > far)
      std::swap (near, far);
    // NaN (0 * inf, a ray in the box's plane) leaves the interval as it is.
    t0 = near > t0 ? near : t0;
    t1 = far < t1 ? far : t1;
    if (t0 > t1)
      return false;
  }
  t_enter = t0;
  return true;
}

/** Closest point of triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5). */
Eigen::Vector3d
closestOnTriangle (const Eigen::Vector3d &p, const Eigen::Vector3d &a, const Eigen::Vector3d &b, const Eigen::Vector3d &c)
{
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot (ap), d2 = ac.dot (ap);
  if (d1 <= 0 && d2 <= 0)
    return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot (bp), d4 = ac.dot (bp);
  if (d3 >= 0 && d4 <= d3)
    return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
    return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot (cp), d6 = ac.dot (cp);
  if (d6 >= 0 && d5 <= d6)
    return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0)
    return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double sum = va + vb + vc;
  if (!(sum > 0.0))
  {
    // A degenerate triangle (collinear corners): the nearest of its edges.
    auto onSegment = [&] (const Eigen::Vector3d &s, const Eigen::Vector3d &e) {
      const Eigen::Vector3d se = e - s;
      const double len2 = se.squaredNorm ();
      return Eigen::Vector3d (len2 > 0 ? s + se * std::clamp ((p - s).dot (se) / len2, 0.0, 1.0) : s);
    };
    Eigen::Vector3d best = onSegment (a, b);
    for (const Eigen::Vector3d &q : {onSegment (b, c), onSegment (c, a)})
      if ((q - p).squaredNorm () < (best - p).squaredNorm ())
        best = q;
    return best;
  }
  const double denom = 1.0 / sum;
  return a + ab * (vb * denom) + ac * (vc * denom);
}
}  // namespace

SynthMesh::SynthMesh (std::vector<Eigen::Vector3d> vertices, std::vector<Eigen::Vector3i> triangles)
  : vertices_ (std::move (vertices)), triangles_ (std::move (triangles))
{
  const int n = static_cast<int> (vertices_.size ());
  for (const auto &v : vertices_)
    if (!v.allFinite ())
      throw std::invalid_argument ("SynthMesh: a vertex is not finite");
  for (const auto &t : triangles_)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= n)
        throw std::invalid_argument ("SynthMesh: triangle vertex " + std::to_string (t[k]) + " out of range (" +
                                     std::to_string (n) + " vertices)");
  if (!vertices_.empty ())
  {
    Eigen::AlignedBox3d all;
    for (const auto &v : vertices_)
      all.extend (v);
    sphere_centre_ = all.center ();
    for (const auto &v : vertices_)
      sphere_radius_ = std::max (sphere_radius_, (v - sphere_centre_).norm ());
  }
  if (triangles_.empty ())
    return;
  std::vector<Eigen::Vector3d> centroids (triangles_.size ());
  order_.resize (triangles_.size ());
  for (std::size_t i = 0; i < triangles_.size (); ++i)
  {
    const auto &t = triangles_[i];
    centroids[i] = (vertices_[t[0]] + vertices_[t[1]] + vertices_[t[2]]) / 3.0;
    order_[i] = static_cast<int> (i);
  }
  nodes_.reserve (2 * triangles_.size () / kLeafSize + 1);
  build (0, static_cast<int> (triangles_.size ()), centroids);
}

int
SynthMesh::build (int begin, int end, std::vector<Eigen::Vector3d> &centroids)
{
  const int index = static_cast<int> (nodes_.size ());
  nodes_.emplace_back ();
  Eigen::AlignedBox3d box, centre_box;
  for (int i = begin; i < end; ++i)
  {
    const auto &t = triangles_[order_[i]];
    for (int k = 0; k < 3; ++k)
      box.extend (vertices_[t[k]]);
    centre_box.extend (centroids[order_[i]]);
  }
  nodes_[index].box = box;
  if (end - begin <= kLeafSize)
  {
    nodes_[index].first = begin;
    nodes_[index].count = end - begin;
    return index;
  }
  int axis = 0;
  centre_box.sizes ().maxCoeff (&axis);
  const int mid = (begin + end) / 2;
  std::nth_element (order_.begin () + begin, order_.begin () + mid, order_.begin () + end,
                    [&] (int a, int b) { return centroids[a][axis] < centroids[b][axis]; });
  build (begin, mid, centroids);
  const int right = build (mid, end, centroids);
  nodes_[index].first = right;
  nodes_[index].count = 0;
  return index;
}

double
SynthMesh::intersect (const Eigen::Vector3d &o, const Eigen::Vector3d &d, double t_min, Eigen::Vector3d *normal,
                      int *triangle) const
{
  if (nodes_.empty ())
    return -1.0;
  const Eigen::Vector3d inv (1.0 / d.x (), 1.0 / d.y (), 1.0 / d.z ());
  double best = kInf;
  int best_triangle = -1;
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0)
  {
    const Node &node = nodes_[stack[--top]];
    double enter;
    if (!slab (node.box, o, inv, best, enter))
      continue;
    if (node.count == 0)
    {
      const int left = static_cast<int> (&node - nodes_.data ()) + 1, right = node.first;
      // Depth is at most log2(triangles / 4) + 1, far below the stack's size.
      stack[top++] = right;
      stack[top++] = left;
      continue;
    }
    for (int i = node.first; i < node.first + node.count; ++i)
    {
      // Moller-Trumbore.
      const auto &t = triangles_[order_[i]];
      const Eigen::Vector3d &a = vertices_[t[0]];
      const Eigen::Vector3d e1 = vertices_[t[1]] - a, e2 = vertices_[t[2]] - a;
      const Eigen::Vector3d p = d.cross (e2);
      const double det = e1.dot (p);
      if (std::abs (det) < 1e-18)
        continue;
      const double inv_det = 1.0 / det;
      const Eigen::Vector3d s = o - a;
      const double u = s.dot (p) * inv_det;
      if (u < -kEdgeSlack || u > 1.0 + kEdgeSlack)
        continue;
      const Eigen::Vector3d q = s.cross (e1);
      const double v = d.dot (q) * inv_det;
      if (v < -kEdgeSlack || u + v > 1.0 + kEdgeSlack)
        continue;
      const double hit = e2.dot (q) * inv_det;
      if (hit > t_min && hit < best)
      {
        best = hit;
        best_triangle = order_[i];
      }
    }
  }
  if (best_triangle < 0)
    return -1.0;
  if (triangle)
    *triangle = best_triangle;
  if (normal)
  {
    const auto &t = triangles_[best_triangle];
    Eigen::Vector3d n = (vertices_[t[1]] - vertices_[t[0]]).cross (vertices_[t[2]] - vertices_[t[0]]).normalized ();
    *normal = n.dot (d) > 0 ? Eigen::Vector3d (-n) : n;
  }
  return best;
}

double
SynthMesh::distance (const Eigen::Vector3d &p) const
{
  if (nodes_.empty ())
    return kInf;
  double best2 = kInf;
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0)
  {
    const Node &node = nodes_[stack[--top]];
    if (node.box.squaredExteriorDistance (p) >= best2)
      continue;
    if (node.count == 0)
    {
      stack[top++] = node.first;
      stack[top++] = static_cast<int> (&node - nodes_.data ()) + 1;
      continue;
    }
    for (int i = node.first; i < node.first + node.count; ++i)
    {
      const auto &t = triangles_[order_[i]];
      best2 = std::min (best2, (p - closestOnTriangle (p, vertices_[t[0]], vertices_[t[1]], vertices_[t[2]])).squaredNorm ());
    }
  }
  return std::sqrt (best2);
}
}  // namespace agex

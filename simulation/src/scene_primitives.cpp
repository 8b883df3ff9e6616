// Scene primitives and their ray intersections.
#include <agex/simulation/scene_primitives.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace agex
{
namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity ();

Eigen::Matrix3d
inverseOfOrthogonalColumns (const Eigen::Matrix3d &axes)
{
  Eigen::Matrix3d inv = axes.transpose ();
  for (int i = 0; i < 3; ++i)
  {
    const double n2 = axes.col (i).squaredNorm ();
    inv.row (i) /= n2 > 0 ? n2 : 1.0;
  }
  return inv;
}

/** Ray-sphere: nearest t > t_min, -1 if none. */
inline double
sphereHit (const Eigen::Vector3d &o, const Eigen::Vector3d &d, const Eigen::Vector3d &c, double r, double t_min)
{
  const Eigen::Vector3d oc = o - c;
  const double b = oc.dot (d);
  const double cc = oc.squaredNorm () - r * r;
  const double h = b * b - cc;
  if (h < 0)
    return -1.0;
  const double s = std::sqrt (h);
  if (-b - s > t_min)
    return -b - s;
  if (-b + s > t_min)
    return -b + s;
  return -1.0;
}
}  // namespace

SynthPrimitive
SynthPrimitive::capsule (const Eigen::Vector3d &a, const Eigen::Vector3d &b, double radius, SynthObject object)
{
  SynthPrimitive p;
  p.shape = Shape::Capsule;
  p.object = object;
  p.a = a;
  p.b = b;
  p.radius = radius;
  return p;
}

SynthPrimitive
SynthPrimitive::ellipsoid (const Eigen::Vector3d &centre, const Eigen::Matrix3d &axes, SynthObject object)
{
  SynthPrimitive p;
  p.shape = Shape::Ellipsoid;
  p.object = object;
  p.centre = centre;
  p.axes = axes;
  p.inverse = inverseOfOrthogonalColumns (axes);
  return p;
}

SynthPrimitive
SynthPrimitive::box (const Eigen::Vector3d &centre, const Eigen::Matrix3d &axes, SynthObject object)
{
  SynthPrimitive p = ellipsoid (centre, axes, object);
  p.shape = Shape::Box;
  return p;
}

SynthPrimitive
SynthPrimitive::plane (const Eigen::Vector3d &normal, double offset, SynthObject object)
{
  SynthPrimitive p;
  p.shape = Shape::Plane;
  p.object = object;
  const double n = normal.norm ();
  p.normal = normal / n;
  p.offset = offset / n;
  return p;
}

SynthPrimitive
SynthPrimitive::triangleMesh (std::shared_ptr<const SynthMesh> mesh, SynthObject object)
{
  if (!mesh)
    throw std::invalid_argument ("SynthPrimitive::triangleMesh: no mesh");
  SynthPrimitive p;
  p.shape = Shape::Mesh;
  p.object = object;
  p.mesh = std::move (mesh);
  return p;
}

SynthPrimitive
SynthPrimitive::transformed (const Eigen::Isometry3d &t) const
{
  SynthPrimitive p = *this;
  p.a = t * a;
  p.b = t * b;
  p.centre = t * centre;
  p.axes = t.linear () * axes;
  p.inverse = inverseOfOrthogonalColumns (p.axes);
  p.normal = t.linear () * normal;
  p.offset = offset + p.normal.dot (t.translation ());
  return p;
}

bool
SynthPrimitive::boundingSphere (Eigen::Vector3d &c, double &r) const
{
  switch (shape)
  {
    case Shape::Capsule:
      c = 0.5 * (a + b);
      r = 0.5 * (b - a).norm () + radius;
      return true;
    case Shape::Ellipsoid:
      c = centre;
      r = std::max ({axes.col (0).norm (), axes.col (1).norm (), axes.col (2).norm ()});
      return true;
    case Shape::Box:
      c = centre;
      r = std::sqrt (axes.col (0).squaredNorm () + axes.col (1).squaredNorm () + axes.col (2).squaredNorm ());
      return true;
    case Shape::Mesh:
      c = centre + axes * mesh->sphereCentre ();
      r = mesh->sphereRadius ();
      return true;
    case Shape::Plane: return false;
  }
  return false;
}

double
SynthPrimitive::intersect (const Eigen::Vector3d &o, const Eigen::Vector3d &d, double t_min, Eigen::Vector3d *n,
                           int *triangle) const
{
  if (triangle)
    *triangle = -1;
  switch (shape)
  {
    case Shape::Capsule:
    {
      // Cylinder body (Inigo Quilez's formulation) and both end spheres.
      const Eigen::Vector3d ba = b - a, oa = o - a;
      const double baba = ba.squaredNorm (), bard = ba.dot (d), baoa = ba.dot (oa);
      const double rdoa = d.dot (oa), oaoa = oa.squaredNorm ();
      double best = -1.0;
      Eigen::Vector3d best_normal = Eigen::Vector3d::Zero ();
      const double qa = baba - bard * bard;
      if (qa > 1e-12 * baba)
      {
        const double qb = baba * rdoa - baoa * bard;
        const double qc = baba * oaoa - baoa * baoa - radius * radius * baba;
        const double h = qb * qb - qa * qc;
        if (h >= 0)
        {
          const double s = std::sqrt (h);
          for (const double t : {(-qb - s) / qa, (-qb + s) / qa})
          {
            const double y = baoa + t * bard;
            if (t > t_min && y > 0 && y < baba)
            {
              best = t;
              if (n)
                best_normal = (oa + t * d - ba * (y / baba)) / radius;
              break;
            }
          }
        }
      }
      for (const Eigen::Vector3d *c : {&a, &b})
      {
        const double t = sphereHit (o, d, *c, radius, t_min);
        if (t > t_min && (best < 0 || t < best))
        {
          best = t;
          if (n)
            best_normal = (o + t * d - *c) / radius;
        }
      }
      if (n && best > 0)
        *n = best_normal;
      return best;
    }
    case Shape::Ellipsoid:
    {
      const Eigen::Vector3d lo = inverse * (o - centre), ld = inverse * d;
      const double qa = ld.squaredNorm (), qb = lo.dot (ld), qc = lo.squaredNorm () - 1.0;
      const double h = qb * qb - qa * qc;
      if (h < 0)
        return -1.0;
      const double s = std::sqrt (h);
      double t = (-qb - s) / qa;
      if (t <= t_min)
        t = (-qb + s) / qa;
      if (t <= t_min)
        return -1.0;
      if (n)
        *n = (inverse.transpose () * (lo + t * ld)).normalized ();
      return t;
    }
    case Shape::Box:
    {
      const Eigen::Vector3d lo = inverse * (o - centre), ld = inverse * d;
      double t_near = -kInf, t_far = kInf;
      int axis_near = 0, axis_far = 0;
      for (int i = 0; i < 3; ++i)
      {
        if (std::abs (ld[i]) < 1e-15)
        {
          if (std::abs (lo[i]) > 1.0)
            return -1.0;
          continue;
        }
        double t1 = (-1.0 - lo[i]) / ld[i], t2 = (1.0 - lo[i]) / ld[i];
        if (t1 > t2)
          std::swap (t1, t2);
        if (t1 > t_near)
        {
          t_near = t1;
          axis_near = i;
        }
        if (t2 < t_far)
        {
          t_far = t2;
          axis_far = i;
        }
      }
      if (t_near > t_far)
        return -1.0;
      double t = t_near;
      int axis = axis_near;
      if (t <= t_min)
      {
        t = t_far;
        axis = axis_far;
      }
      if (t <= t_min)
        return -1.0;
      if (n)
      {
        const double side = (lo[axis] + t * ld[axis]) >= 0 ? 1.0 : -1.0;
        *n = side * axes.col (axis).normalized ();
      }
      return t;
    }
    case Shape::Plane:
    {
      const double denom = normal.dot (d);
      if (std::abs (denom) < 1e-12)
        return -1.0;
      const double t = (offset - normal.dot (o)) / denom;
      if (t <= t_min)
        return -1.0;
      if (n)
        *n = denom < 0 ? normal : Eigen::Vector3d (-normal);
      return t;
    }
    case Shape::Mesh:
    {
      // The placement is rigid, so t is the same in the mesh's own frame.
      const double t = mesh->intersect (axes.transpose () * (o - centre), axes.transpose () * d, t_min, n, triangle);
      if (t >= 0 && n)
        *n = axes * *n;
      return t;
    }
  }
  return -1.0;
}

SynthPart
SynthPrimitive::partAt (int triangle) const
{
  if (object != SynthObject::Person)
    return SynthPart::None;
  SynthPart p = part;
  if (triangle_parts && triangle >= 0 && static_cast<std::size_t> (triangle) < triangle_parts->size ())
    p = (*triangle_parts)[static_cast<std::size_t> (triangle)];
  return p == SynthPart::None ? SynthPart::Unknown : p;
}

double
SynthPrimitive::distance (const Eigen::Vector3d &p) const
{
  switch (shape)
  {
    case Shape::Capsule:
    {
      const Eigen::Vector3d ba = b - a;
      const double len2 = ba.squaredNorm ();
      const double t = len2 > 0 ? std::clamp ((p - a).dot (ba) / len2, 0.0, 1.0) : 0.0;
      return (p - (a + t * ba)).norm () - radius;
    }
    case Shape::Ellipsoid:
    {
      // p/r and p/r^2 in the ellipsoid's own frame (Quilez's bound, exact on the surface).
      const Eigen::Vector3d q = inverse * (p - centre);
      Eigen::Vector3d q2;
      for (int i = 0; i < 3; ++i)
        q2[i] = q[i] / axes.col (i).norm ();
      const double k0 = q.norm (), k1 = q2.norm ();
      return k1 > 0 ? k0 * (k0 - 1.0) / k1 : -axes.col (0).norm ();
    }
    case Shape::Box:
    {
      Eigen::Vector3d d;
      for (int i = 0; i < 3; ++i)
      {
        const double h = axes.col (i).norm ();
        d[i] = std::abs ((p - centre).dot (axes.col (i)) / h) - h;
      }
      const Eigen::Vector3d outside = d.cwiseMax (0.0);
      return outside.norm () + std::min (d.maxCoeff (), 0.0);
    }
    case Shape::Plane: return normal.dot (p) - offset;
    case Shape::Mesh: return mesh->distance (axes.transpose () * (p - centre));
  }
  return kInf;
}

SynthScene
SynthScene::transformed (const Eigen::Isometry3d &transform) const
{
  SynthScene s;
  s.primitives.reserve (primitives.size ());
  for (const auto &p : primitives)
    s.primitives.push_back (p.transformed (transform));
  return s;
}

double
SynthScene::distance (const Eigen::Vector3d &p, SynthObject object) const
{
  double best = kInf;
  for (const auto &prim : primitives)
    if (prim.object == object)
      best = std::min (best, prim.distance (p));
  return best;
}
}  // namespace agex

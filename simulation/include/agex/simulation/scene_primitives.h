#pragma once
// What a synthetic scene is made of: capsules, ellipsoids, boxes, planes and triangle meshes,
// each tagged with what it belongs to (room, person, body part), and their ray hits.
#include <agex/simulation/synth_mesh.h>
#include <agex/simulation/synth_part.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <vector>

namespace agex
{
/** What a primitive (and a rendered pixel) belongs to. */
enum class SynthObject : std::uint8_t
{
  None = 0,
  Floor = 1,
  Wall = 2,
  Clutter = 3,
  Person = 4
};

/** What a body surface is dressed in, for colour frames (SynthOptions::colour); the
  * room's surfaces take their colour from their SynthObject. */
enum class SynthMaterial : std::uint8_t
{
  Default = 0,
  Skin = 1,    ///< head, neck, hands
  Top = 2,     ///< torso and arms
  Bottom = 3,  ///< legs
  Shoes = 4
};

struct SynthPrimitive
{
  enum class Shape
  {
    Capsule,    ///< segment a-b, radius
    Ellipsoid,  ///< centre, axes (columns: orthogonal semi-axis vectors)
    Box,        ///< centre, axes (columns: orthogonal half-extent vectors)
    Plane,      ///< normal . x = offset (infinite)
    Mesh        ///< triangles of `mesh`, placed by the rotation `axes` and the translation `centre`
  };
  Shape shape = Shape::Capsule;
  SynthObject object = SynthObject::None;
  float reflectivity = 0.7f;  ///< 0..1, for the time-of-flight amplitude
  SynthMaterial material = SynthMaterial::Default;
  /** The body part a Person primitive is, for the per-pixel part labels (None: the
    * label is SynthPart::Unknown, "body, part unknown"). */
  SynthPart part = SynthPart::None;
  /** Meshes: the part of each triangle (parallel to mesh->triangles ()), overriding
    * `part`; null for one part per primitive. */
  std::shared_ptr<const std::vector<SynthPart>> triangle_parts;
  /** Which person (1, 2, ...) a Person primitive belongs to, for the person labels. */
  std::uint8_t person = 1;
  Eigen::Vector3d a = Eigen::Vector3d::Zero (), b = Eigen::Vector3d::Zero ();
  double radius = 0.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero ();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity ();
  Eigen::Matrix3d inverse = Eigen::Matrix3d::Identity ();  ///< axes^-1 (kept by the factories)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY ();
  double offset = 0.0;
  std::shared_ptr<const SynthMesh> mesh;

  static SynthPrimitive capsule (const Eigen::Vector3d &a, const Eigen::Vector3d &b, double radius, SynthObject object);
  static SynthPrimitive ellipsoid (const Eigen::Vector3d &centre, const Eigen::Matrix3d &axes, SynthObject object);
  static SynthPrimitive box (const Eigen::Vector3d &centre, const Eigen::Matrix3d &axes, SynthObject object);
  static SynthPrimitive plane (const Eigen::Vector3d &normal, double offset, SynthObject object);
  /** A triangle mesh in the scene's frame (identity placement). */
  static SynthPrimitive triangleMesh (std::shared_ptr<const SynthMesh> mesh, SynthObject object);

  /** The same primitive after a rigid transform. */
  SynthPrimitive transformed (const Eigen::Isometry3d &transform) const;
  /** Bounding sphere; false for a plane (unbounded). */
  bool boundingSphere (Eigen::Vector3d &centre, double &radius) const;
  /** \brief Nearest ray hit at t > t_min along origin + t * direction (direction of
    * unit length); sets the outward unit normal and, for meshes, the triangle hit (-1
    * for other shapes). Returns -1 if none. */
  double intersect (const Eigen::Vector3d &origin, const Eigen::Vector3d &direction, double t_min,
                    Eigen::Vector3d *normal, int *triangle = nullptr) const;
  /** The part label of a hit on this primitive (triangle from intersect): the
    * triangle's part for meshes with triangle_parts, else `part`; Unknown for a Person
    * primitive without one, None for the room. */
  SynthPart partAt (int triangle) const;
  /** Approximate signed distance of p to the surface (exact for capsules, boxes and
    * planes, first order for ellipsoids); negative inside. Meshes give the unsigned
    * distance. */
  double distance (const Eigen::Vector3d &p) const;
};

/** A scene in one coordinate frame. */
struct SynthScene
{
  std::vector<SynthPrimitive> primitives;
  SynthScene transformed (const Eigen::Isometry3d &transform) const;
  /** Smallest signed distance of p to the primitives of one object class (+inf if none). */
  double distance (const Eigen::Vector3d &p, SynthObject object) const;
};
}  // namespace agex

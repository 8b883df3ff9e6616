// The room around synthetic people: floor, walls, furniture-sized clutter (doc/synthetic.md,
// "Camera and room").
#include <agex/simulation/room.h>

#include <algorithm>
#include <cmath>

namespace agex
{
namespace
{
/** Moves a wall (normal . x = offset, normal towards the people) behind every person's
  * primitive. */
double
clearOfPeople (const RoomFrame &room, const Eigen::Vector3d &normal, double offset)
{
  for (const auto &p : *room.people)
  {
    Eigen::Vector3d c;
    double r;
    p.boundingSphere (c, r);
    offset = std::min (offset, normal.dot (c) - r - 0.05);
  }
  return offset;
}


/** A spot on the floor for a piece of clutter of the given half diagonal: in the
  * clutter area, clear of the people (10 cm) and the camera (40 cm), in front of the
  * walls; false after 20 attempts. */
bool
placeClutter (SynthRng &rng, const RoomFrame &room, double wall_behind, const SynthScene &world, double half_diagonal,
              Eigen::Vector3d &at)
{
  for (int attempt = 0; attempt < 20; ++attempt)
  {
    // Drawn across first, then along: the order earlier builds evaluated them in.
    const double across = rng.uniform (-room.across, room.across);
    const double along = rng.uniform (room.along_min, wall_behind);
    at = room.anchor + room.ahead * along + room.lateral * across;
    at.y () = room.floor_y;
    bool ok = true;
    for (const auto &p : *room.people)
    {
      Eigen::Vector3d c;
      double r;
      p.boundingSphere (c, r);
      const Eigen::Vector2d dxz (c.x () - at.x (), c.z () - at.z ());
      ok = ok && dxz.norm () > half_diagonal + r + 0.1;
    }
    const Eigen::Vector2d to_camera (room.camera.x () - at.x (), room.camera.z () - at.z ());
    ok = ok && to_camera.norm () > half_diagonal + 0.4;
    for (const auto &p : world.primitives)  // in front of the walls
      if (p.object == SynthObject::Wall)
        ok = ok && p.normal.dot (at) - p.offset > half_diagonal + 0.02;
    if (ok)
      return true;
  }
  return false;
}

/** A clutter box turned by `yaw` about the vertical. */
void
addClutterBox (SynthScene &world, const Eigen::Vector3d &centre, const Eigen::Vector3d &half, double yaw, float refl)
{
  const Eigen::Matrix3d r = Eigen::AngleAxisd (yaw, Eigen::Vector3d::UnitY ()).toRotationMatrix ();
  SynthPrimitive b = SynthPrimitive::box (centre, r * half.asDiagonal (), SynthObject::Clutter);
  b.reflectivity = refl;
  world.primitives.push_back (b);
}

/** A desk: a top at 0.70-0.76 m on four legs, roughly facing the camera. */
void
addDesk (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world)
{
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();
  const double half_z = rng.uniform (0.3, 0.4);  // last first: the order earlier builds used
  const double half_x = rng.uniform (0.5, 0.8);
  const Eigen::Vector3d half (half_x, 0.015, half_z);
  const double top = rng.uniform (0.70, 0.76);
  const double yaw = std::atan2 (room.ahead.x (), room.ahead.z ()) + rng.uniform (-0.3, 0.3);
  const float refl = static_cast<float> (rng.uniform (0.3, 0.9));
  Eigen::Vector3d at;
  if (!placeClutter (rng, room, wall_behind, world, std::hypot (half.x (), half.z ()), at))
    return;
  addClutterBox (world, at + up * (top - half.y ()), half, yaw, refl);
  const Eigen::Matrix3d r = Eigen::AngleAxisd (yaw, up).toRotationMatrix ();
  for (const double sx : {-1.0, 1.0})
    for (const double sz : {-1.0, 1.0})
    {
      const Eigen::Vector3d leg = at + r * Eigen::Vector3d (sx * (half.x () - 0.04), 0, sz * (half.z () - 0.04));
      addClutterBox (world, leg + up * (0.5 * (top - 2 * half.y ())),
                     Eigen::Vector3d (0.02, 0.5 * (top - 2 * half.y ()), 0.02), yaw, refl);
    }
}

/** A box 0.2-0.7 m wide and 0.16-1 m tall standing on the floor. */
void
addBox (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world)
{
  const double hz = rng.uniform (0.1, 0.35), hy = rng.uniform (0.08, 0.5), hx = rng.uniform (0.1, 0.35);  // last first
  const Eigen::Vector3d half (hx, hy, hz);
  const double yaw = rng.uniform (0.0, M_PI);
  const float refl = static_cast<float> (rng.uniform (0.3, 0.9));
  Eigen::Vector3d at;
  if (placeClutter (rng, room, wall_behind, world, std::hypot (half.x (), half.z ()), at))
    addClutterBox (world, at + Eigen::Vector3d::UnitY () * half.y (), half, yaw, refl);
}

/** A chair: a seat 0.4-0.5 m wide at 0.42-0.48 m on four legs, a backrest 0.35-0.5 m
  * tall, turned at random. */
void
addChair (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world)
{
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();
  const double half_w = rng.uniform (0.2, 0.25);
  const double seat = rng.uniform (0.42, 0.48);
  const double back = rng.uniform (0.35, 0.5);
  const double yaw = rng.uniform (0.0, 2.0 * M_PI);
  const float refl = static_cast<float> (rng.uniform (0.3, 0.9));
  Eigen::Vector3d at;
  if (!placeClutter (rng, room, wall_behind, world, std::sqrt (2.0) * half_w, at))
    return;
  const Eigen::Matrix3d r = Eigen::AngleAxisd (yaw, up).toRotationMatrix ();
  const double t = 0.015;  // half the thickness of the seat and the backrest
  addClutterBox (world, at + up * (seat - t), Eigen::Vector3d (half_w, t, half_w), yaw, refl);
  for (const double sx : {-1.0, 1.0})
    for (const double sz : {-1.0, 1.0})
    {
      const Eigen::Vector3d leg = at + r * Eigen::Vector3d (sx * (half_w - 0.02), 0, sz * (half_w - 0.02));
      addClutterBox (world, leg + up * (0.5 * (seat - 2 * t)), Eigen::Vector3d (0.015, 0.5 * (seat - 2 * t), 0.015), yaw,
                     refl);
    }
  addClutterBox (world, at + r * Eigen::Vector3d (0, 0, -(half_w - t)) + up * (seat + 0.5 * back),
                 Eigen::Vector3d (half_w, 0.5 * back, t), yaw, refl);
}

/** A shelf facing the camera near the back wall (within 0.6 m of where the wall was
  * drawn): 0.6-1.2 m wide, 0.3-0.4 m deep, 1.2-2 m tall; two sides, a back, a bottom, a
  * top and 1-3 boards between. */
void
addShelf (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world)
{
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();
  const double half_w = rng.uniform (0.3, 0.6);
  const double half_d = rng.uniform (0.15, 0.2);
  const double height = rng.uniform (1.2, 2.0);
  const int boards = 1 + rng.index (3);
  const double yaw = std::atan2 (room.ahead.x (), room.ahead.z ()) + rng.uniform (-0.3, 0.3);
  const float refl = static_cast<float> (rng.uniform (0.3, 0.9));
  Eigen::Vector3d at;
  RoomFrame by_the_wall = room;
  by_the_wall.along_min = wall_behind - 0.6;
  if (!placeClutter (rng, by_the_wall, wall_behind, world, std::hypot (half_w, half_d), at))
    return;
  const Eigen::Matrix3d r = Eigen::AngleAxisd (yaw, up).toRotationMatrix ();  // local +z: away from the camera
  const double t = 0.01;
  for (const double sx : {-1.0, 1.0})
    addClutterBox (world, at + r * Eigen::Vector3d (sx * (half_w - t), 0, 0) + up * (0.5 * height),
                   Eigen::Vector3d (t, 0.5 * height, half_d), yaw, refl);
  addClutterBox (world, at + r * Eigen::Vector3d (0, 0, half_d - t) + up * (0.5 * height),
                 Eigen::Vector3d (half_w - 2 * t, 0.5 * height, t), yaw, refl);
  for (int b = 0; b <= boards + 1; ++b)
    addClutterBox (world, at + up * (t + b * (height - 2 * t) / (boards + 1)),
                   Eigen::Vector3d (half_w - 2 * t, t, half_d - 2 * t), yaw, refl);
}
}  // namespace

/** Adds the floor, the back wall `wall_behind` beyond the anchor (turned by up to 30
  * degrees) and, in half the frames, a side wall; returns wall_behind. */
double
addFloorAndWalls (SynthRng &rng, const RoomFrame &room, SynthScene &world)
{
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();
  SynthPrimitive floor = SynthPrimitive::plane (up, room.floor_y, SynthObject::Floor);
  floor.reflectivity = static_cast<float> (rng.uniform (0.25, 0.6));
  world.primitives.push_back (floor);

  const double wall_behind = rng.uniform (0.7, 2.0);
  const double wall_yaw = rng.uniform (-30.0, 30.0) * M_PI / 180.0;
  {
    const Eigen::Vector3d normal = -(Eigen::AngleAxisd (wall_yaw, up) * room.ahead);
    Eigen::Vector3d at = room.anchor + room.ahead * wall_behind;
    const double offset = clearOfPeople (room, normal, normal.dot (at));
    SynthPrimitive wall = SynthPrimitive::plane (normal, offset, SynthObject::Wall);
    wall.reflectivity = static_cast<float> (rng.uniform (0.5, 0.9));
    world.primitives.push_back (wall);
  }
  const bool side_wall = rng.chance (0.5);
  const double side_sign = rng.chance (0.5) ? 1.0 : -1.0, side_distance = rng.uniform (1.0, 2.5);
  const float side_reflectivity = static_cast<float> (rng.uniform (0.5, 0.9));
  if (side_wall)
  {
    const Eigen::Vector3d normal = -side_sign * room.lateral;
    const double offset =
        clearOfPeople (room, normal, normal.dot (room.anchor + side_sign * room.lateral * side_distance));
    if (normal.dot (room.camera) - offset > 0.3)
    {
      SynthPrimitive wall = SynthPrimitive::plane (normal, offset, SynthObject::Wall);
      wall.reflectivity = side_reflectivity;
      world.primitives.push_back (wall);
    }
  }
  return wall_behind;
}

/** The clutter of a scene with several people: a desk (30%), 0-2 chairs, a shelf (30%)
  * and 0-2 boxes. */
void
addGroupClutter (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world)
{
  const bool desk = rng.chance (0.3);
  const int chairs = rng.index (3);
  const bool shelf = rng.chance (0.3);
  const int boxes = rng.index (3);
  if (desk)
    addDesk (rng, room, wall_behind, world);
  for (int c = 0; c < chairs; ++c)
    addChair (rng, room, wall_behind, world);
  if (shelf)
    addShelf (rng, room, wall_behind, world);
  for (int b = 0; b < boxes; ++b)
    addBox (rng, room, wall_behind, world);
}

/** The room of a frame: floor, walls, then a desk (a quarter of the frames) or 0-3 boxes. */
void
addRoom (SynthRng &rng, const RoomFrame &room, SynthScene &world)
{
  const double wall_behind = addFloorAndWalls (rng, room, world);
  const bool desk = rng.chance (0.25);
  const int boxes = desk ? 0 : rng.index (4);
  if (desk)
    addDesk (rng, room, wall_behind, world);
  for (int b = 0; b < boxes; ++b)
    addBox (rng, room, wall_behind, world);
}
}  // namespace agex

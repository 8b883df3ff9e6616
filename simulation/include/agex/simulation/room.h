#pragma once
// The room around synthetic people (doc/synthetic.md, "Camera and room"): a floor, a back
// wall, sometimes a side wall, and furniture-sized clutter (desks, chairs, shelves, boxes)
// kept clear of the people and the camera. Everything is drawn from the caller's SynthRng.
#include <agex/simulation/synthetic_scene.h>

#include <Eigen/Core>

#include <vector>

namespace agex
{
/** Where the room is laid out: on the floor at floor_y, `ahead` the camera's horizontal
  * view direction, `lateral` to its left; walls and clutter are placed from `anchor`
  * (on the floor plan) and kept clear of the people's primitives and of the camera. */
struct RoomFrame
{
  Eigen::Vector3d anchor, ahead, lateral, camera;
  double floor_y = 0.0;
  const std::vector<SynthPrimitive> *people = nullptr;
  /** Clutter stands at anchor + ahead * [along_min, wall distance] + lateral * [-across, across]. */
  double along_min = -1.2, across = 1.8;
};

/** \brief Adds the floor, the back wall `wall_behind` beyond the anchor (turned by up to 30
  * degrees) and, in half the frames, a side wall. \return wall_behind */
double addFloorAndWalls (SynthRng &rng, const RoomFrame &room, SynthScene &world);

/** \brief The clutter of a scene with several people: a desk (30%), 0-2 chairs, a shelf
  * (30%) and 0-2 boxes. */
void addGroupClutter (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world);

/** \brief The room of a one-person frame: floor, walls, then a desk (a quarter of the
  * frames) or 0-3 boxes. */
void addRoom (SynthRng &rng, const RoomFrame &room, SynthScene &world);
}  // namespace agex

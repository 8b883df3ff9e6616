// Colour frames for synthetic scenes (shadeColour, doc/synthetic.md "Colour frames").
//
// 2D models (the contour landmark cascade) trained on depth-shaded renders learn that
// the person is the bright, near thing; photos do not work that way. Here every frame
// draws its own look (domain randomisation): skin tone, clothes, room colours and
// patterns, light. What stays the same across frames is only the outline, which is what
// the models should learn.

#include <agex/simulation/synthetic_scene.h>

#include <algorithm>
#include <cmath>

namespace agex
{
namespace
{
using Rgb = Eigen::Vector3d;  // linear 0..1

/** Three uniform values; drawn last component first, in sequenced statements, so the
  * draws do not depend on the compiler's order of evaluating arguments (this is the
  * order earlier builds happened to use). */
Eigen::Vector3d
randomVector (SynthRng &rng, double lo, double hi)
{
  const double z = rng.uniform (lo, hi);
  const double y = rng.uniform (lo, hi);
  const double x = rng.uniform (lo, hi);
  return Eigen::Vector3d (x, y, z);
}

Rgb
randomColour (SynthRng &rng)
{
  // Half saturated, half muted: clothes and walls are often grey, black or white.
  if (rng.chance (0.4))
    return Rgb::Constant (rng.uniform (0.05, 0.95));
  return randomVector (rng, 0.0, 1.0);
}

Rgb
randomSkin (SynthRng &rng)
{
  // Between dark brown and pale, as in photos of people.
  const Rgb dark (0.30, 0.19, 0.12), pale (0.98, 0.82, 0.70);
  const double t = rng.uniform ();
  return dark + t * (pale - dark);
}

/** A pattern over 3D points: the sum of two plane waves with random direction, period
  * and phase, in [-1, 1]. */
struct Pattern
{
  Eigen::Vector3d k1 = Eigen::Vector3d::Zero (), k2 = Eigen::Vector3d::Zero ();
  double phase1 = 0.0, phase2 = 0.0;

  static Pattern random (SynthRng &rng, double min_period, double max_period)
  {
    Pattern p;
    auto wave = [&] () {
      const double z = rng.normal (), y = rng.normal (), x = rng.normal ();  // last first, as randomVector
      const Eigen::Vector3d d = Eigen::Vector3d (x, y, z).normalized ();
      return Eigen::Vector3d (d * (2.0 * M_PI / rng.uniform (min_period, max_period)));
    };
    p.k1 = wave ();
    p.k2 = wave ();
    p.phase1 = rng.uniform (0.0, 2.0 * M_PI);
    p.phase2 = rng.uniform (0.0, 2.0 * M_PI);
    return p;
  }
  double at (const Eigen::Vector3d &x) const
  {
    return 0.5 * (std::sin (k1.dot (x) + phase1) + std::sin (k2.dot (x) + phase2));
  }
};

struct Look
{
  Rgb material[5];  ///< per SynthMaterial (Default unused on bodies)
  Rgb floor, wall, far;
  std::vector<Rgb> clutter;  ///< per scene primitive index (only clutter ones used)
  Pattern clothes, room;
  double clothes_contrast = 0.0, room_contrast = 0.0;
  Eigen::Vector3d light = -Eigen::Vector3d::UnitY ();  ///< towards the light, camera frame
  double ambient = 0.4;
  double noise = 0.01;  ///< pixel noise sigma
};

Look
randomLook (const SynthFrame &frame, SynthRng &rng)
{
  Look look;
  look.material[static_cast<int> (SynthMaterial::Default)] = randomColour (rng);
  look.material[static_cast<int> (SynthMaterial::Skin)] = randomSkin (rng);
  look.material[static_cast<int> (SynthMaterial::Top)] = randomColour (rng);
  look.material[static_cast<int> (SynthMaterial::Bottom)] = randomColour (rng);
  look.material[static_cast<int> (SynthMaterial::Shoes)] = Rgb::Constant (rng.uniform (0.02, 0.6));
  look.floor = randomColour (rng);
  look.wall = randomColour (rng);
  look.far = randomColour (rng);
  look.clutter.resize (frame.scene.primitives.size ());
  for (auto &c : look.clutter)
    c = randomColour (rng);
  look.clothes = Pattern::random (rng, 0.02, 0.3);
  look.room = Pattern::random (rng, 0.05, 1.5);
  look.clothes_contrast = rng.uniform (0.0, 0.15);
  look.room_contrast = rng.uniform (0.0, 0.5);
  // Light from above and in front of the person, in the world; to the camera frame.
  const double light_z = rng.uniform (-1.0, 1.0), light_y = rng.uniform (0.5, 2.0), light_x = rng.uniform (-1.0, 1.0);
  const Eigen::Vector3d world_dir (light_x, light_y, light_z);
  look.light = (frame.world_to_camera.linear () * world_dir).normalized ();
  look.ambient = rng.uniform (0.25, 0.7);
  look.noise = rng.uniform (0.005, 0.03);
  return look;
}
}  // namespace

void
shadeColour (const SensorModel &sensor, SynthRng &rng, SynthFrame &frame)
{
  const int w = sensor.width, h = sensor.height;
  const std::size_t n = static_cast<std::size_t> (w) * h;
  if (frame.primitive.size () != n)
    throw std::invalid_argument ("shadeColour: the frame was not rendered with this sensor (" + std::to_string (w) +
                                 "x" + std::to_string (h) + ")");
  const Look look = randomLook (frame, rng);
  const CameraIntrinsics &k = sensor.intrinsics;
  std::vector<Rgb> linear (n);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      const int index = frame.primitive[i];
      if (index < 0)
      {
        linear[i] = look.far;
        continue;
      }
      const SynthPrimitive &p = frame.scene.primitives[static_cast<std::size_t> (index)];
      const Eigen::Vector3d ray = Eigen::Vector3d ((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0).normalized ();
      Eigen::Vector3d normal = -ray;
      const double t = p.intersect (Eigen::Vector3d::Zero (), ray, 1e-6, &normal);
      if (normal.dot (ray) > 0.0)  // seen from inside (a plane's back): face the camera
        normal = -normal;
      const Eigen::Vector3d at = ray * std::max (t, 0.0);
      Rgb albedo;
      double texture = 0.0;
      switch (p.object)
      {
      case SynthObject::Person:
        albedo = look.material[static_cast<int> (p.material)];
        texture = look.clothes_contrast * look.clothes.at (at);
        break;
      case SynthObject::Floor:
        albedo = look.floor;
        texture = look.room_contrast * look.room.at (at);
        break;
      case SynthObject::Wall:
        albedo = look.wall;
        texture = look.room_contrast * look.room.at (at);
        break;
      default:
        albedo = look.clutter[static_cast<std::size_t> (index)];
        texture = look.room_contrast * look.room.at (at);
        break;
      }
      const double lambert = std::max (0.0, normal.dot (look.light));
      linear[i] = albedo * ((look.ambient + (1.0 - look.ambient) * lambert) * (1.0 + texture));
    }
  // A lens's blur: 3x3 binomial, so outlines are not single-pixel steps.
  std::vector<Rgb> blurred (n);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      Rgb sum = Rgb::Zero ();
      double weights = 0.0;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du)
        {
          const int uu = u + du, vv = v + dv;
          if (uu < 0 || uu >= w || vv < 0 || vv >= h)
            continue;
          const double weight = (du == 0 ? 2.0 : 1.0) * (dv == 0 ? 2.0 : 1.0);
          sum += weight * linear[static_cast<std::size_t> (vv) * w + uu];
          weights += weight;
        }
      blurred[static_cast<std::size_t> (v) * w + u] = sum / weights;
    }
  frame.colour.assign (n, {0, 0, 0});
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
    {
      // Gamma 2.2 to 8-bit sRGB-like values, as a camera writes them.
      const double value = std::clamp (blurred[i][c] + rng.normal (0.0, look.noise), 0.0, 1.0);
      frame.colour[i][static_cast<std::size_t> (c)] =
          static_cast<std::uint8_t> (std::lround (255.0 * std::pow (value, 1.0 / 2.2)));
    }
}
}  // namespace agex

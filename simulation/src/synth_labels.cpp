// Tip and base labels of rendered people.
#include <agex/simulation/synth_labels.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace agex
{
int
labelWindow (const SensorModel &sensor)
{
  // The Kinect's correlation window hands a pixel to the surface dominating its window, so
  // the surface seen at a tip can lie up to half a window from its pixel (a fingertip of a
  // visible hand shows the wall behind it).
  return sensor.sensor == SynthSensor::Kinect ? std::max (2, sensor.kinect_window / 2) : 1;
}

void
makeLabels (const BodyModel &body, const SensorModel &sensor, SynthFrame &frame)
{
  frame.labels.clear ();
  frame.label_checks.clear ();
  appendPersonLabels (body, sensor, 0, 1, frame);
}

void
appendPersonLabels (const BodyModel &body, const SensorModel &sensor, int first_primitive, int person,
                    SynthFrame &frame)
{
  const CameraIntrinsics &k = sensor.intrinsics;
  const int w = sensor.width, h = sensor.height, win = labelWindow (sensor);
  auto project = [&] (const Eigen::Vector3d &p) {
    const double z = std::max (p.z (), 1e-3);
    return Eigen::Vector2f (static_cast<float> (k.fx * p.x () / z + k.cx), static_cast<float> (k.fy * p.y () / z + k.cy));
  };
  auto visible = [&] (int index, const Eigen::Vector2f &px) {
    const Eigen::Vector3d &tip = body.tip[index];
    if (tip.z () < 0.05)
      return false;
    const long u = std::lround (px.x ()), v = std::lround (px.y ());
    if (u < 0 || v < 0 || u >= w || v >= h)
      return false;
    std::vector<int> own = body.tip_primitives[index];
    for (int &p : own)
      p += first_primitive;
    for (long vv = std::max (0L, v - win); vv <= std::min<long> (h - 1, v + win); ++vv)
      for (long uu = std::max (0L, u - win); uu <= std::min<long> (w - 1, u + win); ++uu)
      {
        const std::size_t i = static_cast<std::size_t> (vv) * w + uu;
        const float z = frame.cloud.points[i].z;
        if (std::isfinite (z) && std::abs (z - tip.z ()) < body.tip_tolerance[index] &&
            std::find (own.begin (), own.end (), frame.primitive[i]) != own.end ())
          return true;
      }
    return false;
  };
  auto label = [&] (BodyPart part, int index) {
    PartLabel l;
    l.part = part;
    l.tip = body.tip[index].cast<float> ();
    l.base = body.base[index].cast<float> ();
    l.tip_px = project (body.tip[index]);
    l.base_px = project (body.base[index]);
    l.visible = l.tip_px.allFinite () && l.base_px.allFinite () && visible (index, l.tip_px);
    if (!l.tip_px.allFinite () || !l.base_px.allFinite ())  // never: guards labels.csv against NaN pixels
      l.tip_px = l.base_px = Eigen::Vector2f (-1.0f, -1.0f);
    l.keyframe = true;
    l.person = person;
    SynthLabelCheck check{body.tip_primitives[index], body.tip_tolerance[index]};
    for (int &p : check.primitives)
      p += first_primitive;
    return std::make_pair (l, check);
  };
  auto push = [&] (const std::pair<PartLabel, SynthLabelCheck> &l) {
    frame.labels.push_back (l.first);
    frame.label_checks.push_back (l.second);
  };
  push (label (BodyPart::Head, 0));
  for (const BodyPart part : {BodyPart::Hand, BodyPart::Foot})
  {
    const int first = part == BodyPart::Hand ? 1 : 3;
    auto a = label (part, first), b = label (part, first + 1);
    if (b.first.tip_px.x () < a.first.tip_px.x ())
      std::swap (a, b);
    a.first.instance = 0;
    b.first.instance = 1;
    push (a);
    push (b);
  }
}
}  // namespace agex

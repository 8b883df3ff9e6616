#pragma once
// The Bonn frames' look (doc/synthetic.md, "Sensor models"): a Kinect v1 frame stored as
// 8-bit depth in kBonnDepthStep steps, seen through the 144x176 portrait view.

#include <agex/simulation/sensor_model.h>
#include <agex/simulation/synthetic_scene.h>

namespace agex
{
/** Makes kinect frames look like the Bonn frames. */
class BonnSensor
{
public:
  /** kinect: the model the frame was rendered with (renderSensorModel (Bonn));
    * bonn: the model of the result (sensorModel (Bonn)). depth_levels false keeps the kinect's
    * depth (only the view): the Bonn frames' 8-bit levels end at 4.09 m, which a scene moved
    * farther away (FrameReprojection) would leave. */
  BonnSensor (const SensorModel &kinect, const SensorModel &bonn, bool depth_levels = true)
    : kinect_ (kinect), bonn_ (bonn), depth_levels_ (depth_levels)
  {
  }

  /** \brief Depth in 8-bit steps of kBonnDepthStep (0 and beyond 255 steps: no
    * measurement; skipped without depth_levels), each point kept on its pixel's ray, then
    * the portrait view (nearest source pixel, as agex_convert bonn does). The ground truth
    * follows the view, so labels are made in it. */
  void apply (SynthFrame &frame) const;

  /** The 8-bit depth of a metric depth: round (z / kBonnDepthStep), 0 (none) outside 1-255. */
  static int depthLevel (double z);

private:
  SensorModel kinect_, bonn_;
  bool depth_levels_ = true;
};

/** The same as BonnSensor (kinect, bonn).apply (frame). */
void toBonnView (const SensorModel &kinect, const SensorModel &bonn, SynthFrame &frame);
}  // namespace agex

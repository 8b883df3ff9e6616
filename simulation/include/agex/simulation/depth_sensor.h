#pragma once
// How a sensor turns the renderer's ideal ray hits into measured depth (doc/synthetic.md,
// "Sensor models"): a base class and one class per model, each in its own file under
// simulation/src/sensors/.

#include <agex/simulation/renderer.h>
#include <agex/simulation/sensor_model.h>

#include <memory>
#include <vector>

namespace agex
{
/** What a sensor makes of one pixel's ideal samples before its noise. */
struct PixelMeasurement
{
  float range = 0.0f;      ///< along the pixel-centre ray, metres
  float amplitude = 0.0f;  ///< time of flight: the returned amplitude
  /** The sample whose surface the range shows (for the part labels); null: none (a
    * flying pixel between surfaces). */
  const RayHit *surface = nullptr;
};

/** The ideal render a sensor measures: the scene (camera frame), the rays, and per
  * pixel (row-major) the range measured before noise (NaN: nothing) and amplitude. */
struct IdealRender
{
  const SynthScene &scene;
  const PixelRays &rays;
  std::vector<float> range;
  std::vector<float> amplitude;
};

/** A depth sensor model (base class). */
class DepthSensor
{
public:
  explicit DepthSensor (const SensorModel &model) : model_ (model) {}
  virtual ~DepthSensor () = default;

  const SensorModel &model () const { return model_; }

  /** Samples per pixel side the renderer casts where a pixel's neighbourhood is not one
    * surface (1: the centre ray only). */
  virtual int samplesPerSide () const { return 1; }
  /** True if the sensor uses IdealRender::amplitude. */
  virtual bool needsAmplitude () const { return false; }

  /** \brief One pixel: the range before noise and the surface it shows; false for no
    * measurement (out of range, too oblique, too faint). */
  virtual bool measurePixel (const PixelSamples &samples, const PixelIntegral &sum, const RayHit &centre,
                             PixelMeasurement &out) const = 0;

  /** \brief The whole frame: noise, shadows, holes and quantisation applied to the
    * ranges, written to frame.cloud (NaN: no measurement); may change frame.clean_z
    * (the depth before noise) and the labels of pixels that now show another surface. */
  virtual void measureFrame (const IdealRender &ideal, SynthRng &rng, SynthFrame &frame) const = 0;

  /** \brief The model of a sensor's parameters.
    * \throws std::invalid_argument for bonn (a kinect render made into the Bonn view,
    * BonnSensor) or a bad setting, naming it */
  static std::unique_ptr<DepthSensor> create (const SensorModel &model);

private:
  SensorModel model_;
};

/** \brief Checks a model's settings; throws std::invalid_argument naming a bad one. */
void checkSensorModel (const SensorModel &model);
}  // namespace agex

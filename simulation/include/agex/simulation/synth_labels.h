#pragma once
// Tip and base labels of the people in a rendered frame, with a depth-tested visibility
// (doc/synthetic.md, "Labels").
#include <agex/simulation/body_model.h>
#include <agex/simulation/sensor_model.h>
#include <agex/simulation/synth_frame.h>

namespace agex
{
/** \brief Labels for the body's tips and bases (camera frame, the body's primitives
  * first in frame.scene), projected with the sensor's intrinsics. A tip is visible if
  * its pixel is in the image and within labelWindow() pixels of it a pixel with a valid
  * depth within the part's tolerance of the tip's depth sees the tip's own part (the
  * noise-free centre ray hits one of its primitives). Instance 0 is the one on the
  * image's left (smaller tip u). Fills frame.labels and frame.label_checks. */
void makeLabels (const BodyModel &body_in_camera, const SensorModel &sensor, SynthFrame &frame);

/** \brief The same for one person of several: appends the five labels of a body whose
  * primitives start at index first_primitive of frame.scene, with PartLabel::person =
  * person (and the checks' primitives as scene indices). */
void appendPersonLabels (const BodyModel &body_in_camera, const SensorModel &sensor, int first_primitive, int person,
                         SynthFrame &frame);

/** Half size of the label visibility window: 1 (3x3) for sr4000, 2 (5x5) for kinect, or
  * half its correlation window if that is larger (4 for kinect_window 9). */
int labelWindow (const SensorModel &sensor);
}  // namespace agex

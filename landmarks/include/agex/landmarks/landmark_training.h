#pragma once
// Training the contour shape predictor and the people detector on annotated images
// (landmark_dataset.h): what agex_landmarks_train does once and the cross-validation
// (landmark_evaluation.h) once per fold. Images are named by index, so that folds share the
// loaded images instead of copying them.

#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/landmark_dataset.h>
#include <agex/landmarks/pasted_people.h>
#include <agex/landmarks/people_crops.h>
#include <agex/landmarks/people_detector.h>

#include <cstddef>
#include <vector>

namespace agex
{
/** \brief Trains the shape predictor on the people of images[which] (square boxes and their
  * 180 landmarks). params.mirror_map is set to mirroredContourLandmark, so that left-right
  * mirrored copies of the images are added: people face both ways. */
ContourShapePredictor trainContourShapePredictor (const std::vector<AnnotatedImage> &images,
                                                  const std::vector<std::size_t> &which,
                                                  ShapePredictorTrainingParams params);

/** How the people detector is trained: the SVM's settings, and the images it sees. */
struct PeopleDetectorTraining
{
  PeopleDetectorTrainingParams params;
  /** Train on the people pasted into each other's photos (agex::pastePeople): people that fill
    * their photos alone teach the detector that a person fills the frame. */
  bool paste_people = true;
  /** Train on the photos as they are (too). */
  bool originals = true;
  PastedPeopleParams pasted;
  /** Also train on the photos' people-free regions (peopleFreeImages: the people and a margin
    * round them cut away), images where every window is a negative. */
  bool backgrounds = false;
  PeopleFreeParams background_params;
  /** When not null: crops[crop_which] pasted into the training photos (pasteCrops), whose own
    * people are then ignore regions. Not owned. */
  const PeopleCrops *crops = nullptr;
  std::vector<std::size_t> crop_which;
  PastedCropsParams crop_params;
};

/** \brief The images[which] with people pasted into each other's photos (agex::pastePeople):
  * the pasted people are the people, the photos' own people and ignore boxes ignore regions. */
PeopleImages pastedPeopleImages (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                                 const PastedPeopleParams &params);

/** \brief Trains the people detector on images[which]: the pasted people and/or the photos as
  * they are (people are their outlines' boxes, ignore boxes ignore regions), the crops pasted
  * into the photos and the photos' people-free regions, as training asks. Boxes the window
  * cannot match are counted in *ignored (PeopleDetector::train).
  * \throws std::runtime_error when training asks for no people at all (neither the photos, the
  * pasted people nor any crop) */
PeopleDetector trainPeopleDetector (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                                    const PeopleDetectorTraining &training, std::size_t *ignored = nullptr);
}  // namespace agex

#include <agex/landmarks/landmark_training.h>

#include <agex/landmarks/contour_annotation.h>

#include <stdexcept>

namespace agex
{
ContourShapePredictor
trainContourShapePredictor (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                            ShapePredictorTrainingParams params)
{
  std::vector<LandmarkTrainingImage> training;
  for (const std::size_t i : which)
  {
    LandmarkTrainingImage t;
    t.grey = images.at (i).grey;
    for (const AnnotatedPerson &person : images[i].people)
    {
      t.boxes.push_back (person.box);
      t.shapes.push_back (person.landmarks);
    }
    training.push_back (std::move (t));
  }
  params.mirror_map.resize (kContourLandmarkCount);
  for (int i = 0; i < kContourLandmarkCount; ++i)
    params.mirror_map[i] = mirroredContourLandmark (i);
  return ContourShapePredictor::train (training, params);
}

PeopleImages
pastedPeopleImages (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                    const PastedPeopleParams &params)
{
  std::vector<cv::Mat> greys;
  std::vector<std::vector<std::vector<cv::Point2f>>> outlines;
  std::vector<std::vector<cv::Rect>> ignore_regions;
  for (const std::size_t i : which)
  {
    greys.push_back (images.at (i).grey);
    outlines.emplace_back ();
    for (const AnnotatedPerson &person : images[i].people)
      outlines.back ().push_back (person.landmarks);
    ignore_regions.push_back (images[i].ignored);
  }
  return pastePeople (greys, outlines, ignore_regions, params);
}

PeopleDetector
trainPeopleDetector (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                     const PeopleDetectorTraining &training, std::size_t *ignored)
{
  const bool with_crops = training.crops && !training.crop_which.empty ();
  if (!training.paste_people && !training.originals && !with_crops)
    throw std::runtime_error ("the people detector needs people to train on: the photos, the pasted people or crops");
  PeopleImages set;
  if (training.paste_people)
    set = pastedPeopleImages (images, which, training.pasted);
  if (training.originals)
    for (const std::size_t i : which)
    {
      set.images.push_back (images.at (i).grey);
      set.boxes.emplace_back ();
      for (const AnnotatedPerson &person : images[i].people)
        set.boxes.back ().push_back (person.tight_box);
      set.ignore.push_back (images[i].ignored);
    }
  const auto append = [&set] (PeopleImages more) {
    for (std::size_t i = 0; i < more.images.size (); ++i)
    {
      set.images.push_back (more.images[i]);
      set.boxes.push_back (std::move (more.boxes[i]));
      set.ignore.push_back (std::move (more.ignore[i]));
    }
  };
  if (with_crops)
    append (pasteCrops (images, which, *training.crops, training.crop_which, training.crop_params));
  if (training.backgrounds)
    append (peopleFreeImages (images, which, training.background_params));
  return PeopleDetector::train (set.images, set.boxes, set.ignore, training.params, ignored);
}
}  // namespace agex

#include <agex/landmarks/landmark_dataset.h>

#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/image_files.h>
#include <agex/landmarks/imglab_dataset.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <stdexcept>

namespace agex
{
const char *const kShoulderPartNames[2] = {"left_shoulder", "right_shoulder"};

std::vector<AnnotatedImage>
loadLandmarkDataset (const std::string &xml_path, std::size_t *boxes_without_landmarks)
{
  const ImglabDataset dataset = readImglabDataset (xml_path);
  std::vector<AnnotatedImage> images;
  std::size_t without_landmarks = 0;
  for (const ImglabImage &entry : dataset.images)
  {
    AnnotatedImage image;
    image.path = resolveImglabImagePath (xml_path, entry.file);
    image.grey = readImage (image.path, cv::IMREAD_GRAYSCALE, "an image of " + xml_path);
    for (const ImglabBox &box : entry.boxes)
    {
      AnnotatedPerson person;
      person.box = box.rect;
      person.landmarks.resize (kContourLandmarkCount);
      int found = 0;
      for (const auto &[name, p] : box.parts)
      {
        const int index = contourLandmarkIndex (name);
        if (index >= 0)
        {
          person.landmarks[index] = p;
          ++found;
        }
      }
      if (box.ignore || found != kContourLandmarkCount)
      {
        if (found != 0 && found != kContourLandmarkCount && !box.ignore)
          throw std::runtime_error (xml_path + ": line " + std::to_string (box.line) + ": a box in " + entry.file +
                                    " has " + std::to_string (found) + " of the " +
                                    std::to_string (kContourLandmarkCount) + " contour landmarks (parts 000-179)");
        without_landmarks += !box.ignore;
        image.ignored.push_back (box.rect);
        continue;
      }
      person.tight_box = cv::boundingRect (person.landmarks);
      const auto a = box.parts.find (kShoulderPartNames[0]), b = box.parts.find (kShoulderPartNames[1]);
      if (a != box.parts.end () && b != box.parts.end ())
      {
        person.has_shoulders = true;
        person.shoulders[0] = a->second;
        person.shoulders[1] = b->second;
      }
      image.people.push_back (std::move (person));
    }
    images.push_back (std::move (image));
  }
  if (boxes_without_landmarks)
    *boxes_without_landmarks = without_landmarks;
  return images;
}
}  // namespace agex

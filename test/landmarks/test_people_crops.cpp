// Person crops and people-free backgrounds for the people detector (people_crops.h): the
// regions cut from a photo never touch its dilated people, crops land where their boxes say,
// folds split the crops, bad crop folders are named, and INRIA's crops in ../shared read as
// the layout doc/landmarks.md describes.

#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/landmark_training.h>
#include <agex/landmarks/people_crops.h>

#include "landmarks/figures.h"
#include "test_support.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

namespace
{
using namespace landmark_test;  // drawFigure, Figure, tempDir

// A photo of noise with one figure (its 180 landmarks) and, when asked, an ignore box.
agex::AnnotatedImage
photoWithFigure (cv::Size size, cv::Point2f centre, float scale, bool with_ignore_box)
{
  const Figure f = drawFigure (size, centre, scale, 0.4f, 0.3f);
  const agex::ContourAnnotation a = agex::annotateContour (f.mask, agex::ContourAnchors ());
  EXPECT_TRUE (a.ok);
  agex::AnnotatedImage image;
  cv::Mat noise (size, CV_8UC1);
  cv::randu (noise, 0, 60);
  image.grey = noise + f.mask * 0.7;
  agex::AnnotatedPerson person;
  person.box = a.box;
  person.landmarks = a.landmarks;
  person.tight_box = cv::boundingRect (a.landmarks);
  image.people.push_back (person);
  if (with_ignore_box)
    image.ignored.push_back (cv::Rect (size.width - 40, 10, 20, 30));
  return image;
}

TEST (PeopleFreeRegions, NeverTouchTheDilatedPeople)
{
  for (const bool ignore_box : {false, true})
    for (const double dilation : {0.0, 0.1, 0.3})
    {
      const agex::AnnotatedImage image = photoWithFigure (cv::Size (600, 300), cv::Point2f (250, 150), 1.2f, ignore_box);
      agex::PeopleFreeParams params;
      params.dilation = dilation;
      const std::vector<cv::Rect> regions = agex::peopleFreeRegions (image, params);
      // Everything the regions must not touch: the filled outline grown by a disc of the
      // dilation, and the ignore box grown likewise.
      const agex::AnnotatedPerson &person = image.people.front ();
      cv::Mat forbidden = cv::Mat::zeros (image.grey.size (), CV_8UC1);
      std::vector<cv::Point> polygon;
      for (const cv::Point2f &p : person.landmarks)
        polygon.emplace_back (cvRound (p.x), cvRound (p.y));
      cv::fillPoly (forbidden, std::vector<std::vector<cv::Point>>{polygon}, cv::Scalar (255));
      const int grow = static_cast<int> (std::floor (dilation * person.tight_box.height));
      if (grow > 0)
        cv::dilate (forbidden, forbidden, cv::getStructuringElement (cv::MORPH_ELLIPSE, cv::Size (2 * grow + 1, 2 * grow + 1)));
      for (const cv::Rect &r : image.ignored)
      {
        const int g = static_cast<int> (std::floor (dilation * r.height));
        cv::rectangle (forbidden, cv::Rect (r.x - g, r.y - g, r.width + 2 * g, r.height + 2 * g), cv::Scalar (255), cv::FILLED);
      }
      ASSERT_FALSE (regions.empty ()) << dilation;
      bool left = false, right = false;
      for (const cv::Rect &r : regions)
      {
        ASSERT_EQ (r & cv::Rect (0, 0, 600, 300), r);
        EXPECT_EQ (cv::countNonZero (forbidden (r)), 0) << r << " dilation " << dilation;
        left |= r.br ().x <= person.tight_box.x;
        right |= r.x >= person.tight_box.br ().x;
      }
      // The figure stands left of the middle: there is room on both sides.
      EXPECT_TRUE (left) << dilation;
      EXPECT_TRUE (right || ignore_box) << dilation;
      // A larger dilation never gives more room.
      if (dilation > 0)
      {
        params.dilation = 0;
        int tight_area = 0, grown_area = 0;
        for (const cv::Rect &r : agex::peopleFreeRegions (image, params))
          tight_area += r.area ();
        for (const cv::Rect &r : regions)
          grown_area += r.area ();
        EXPECT_LT (grown_area, tight_area);
      }
    }
  // An image without people is one region; bad settings are refused.
  agex::AnnotatedImage empty;
  empty.grey = cv::Mat (100, 80, CV_8UC1, cv::Scalar (5));
  const std::vector<cv::Rect> whole = agex::peopleFreeRegions (empty);
  ASSERT_EQ (whole.size (), 1u);
  EXPECT_EQ (whole.front (), cv::Rect (0, 0, 80, 100));
  agex::PeopleFreeParams bad;
  bad.dilation = -1;
  EXPECT_THROW (agex::peopleFreeRegions (empty, bad), std::invalid_argument);
}

TEST (PeopleFreeRegions, ImagesHaveNoPeopleAndTheChosenHeights)
{
  std::vector<agex::AnnotatedImage> images;
  for (int i = 0; i < 4; ++i)
    images.push_back (photoWithFigure (cv::Size (1000, 800), cv::Point2f (400, 400), 2.5f, false));
  agex::PeopleFreeParams params;
  params.min_region_height = params.max_region_height = 200;
  const agex::PeopleImages free = agex::peopleFreeImages (images, {0, 1, 2, 3}, params);
  ASSERT_GE (free.images.size (), 8u);  // a band left and right of each figure
  for (std::size_t i = 0; i < free.images.size (); ++i)
  {
    EXPECT_TRUE (free.boxes[i].empty ());
    EXPECT_EQ (free.images[i].rows, 200);
    EXPECT_EQ (free.images[i].type (), CV_8UC1);
  }
}

// Crops with a bright block where the person box is: pasted, the block lies at the box the
// paste reports, at the heights asked, and the background's own person is an ignore region.
TEST (PastedCrops, BoxesAreWhereThePeopleAre)
{
  const cv::Rect person (16, 16, 64, 128);
  agex::PeopleCrops crops;
  crops.person = person;
  for (int i = 0; i < 5; ++i)
  {
    cv::Mat crop (160, 96, CV_8UC1, cv::Scalar (30));
    crop (person).setTo (cv::Scalar (250));
    crops.images.push_back (crop);
  }
  std::vector<agex::AnnotatedImage> backgrounds;
  for (int i = 0; i < 6; ++i)
  {
    agex::AnnotatedImage b;
    b.grey = cv::Mat (800, 1000, CV_8UC1, cv::Scalar (0));
    agex::AnnotatedPerson someone;
    someone.tight_box = cv::Rect (450, 100, 100, 600);
    b.people.push_back (someone);
    backgrounds.push_back (b);
  }
  agex::PastedCropsParams params;
  params.min_background_height = params.max_background_height = 400;
  params.min_height = 64;
  params.max_height = 128;
  params.people_per_image = 2;
  const agex::PeopleImages pasted = agex::pasteCrops (backgrounds, {0, 1, 2, 3, 4, 5}, crops, {0, 2, 4}, params);
  ASSERT_EQ (pasted.images.size (), 6u);
  std::set<int> heights;
  for (std::size_t i = 0; i < pasted.images.size (); ++i)
  {
    const cv::Mat &canvas = pasted.images[i];
    EXPECT_EQ (canvas.rows, 400);
    EXPECT_EQ (canvas.cols, 500);
    ASSERT_EQ (pasted.boxes[i].size (), 2u);
    ASSERT_EQ (pasted.ignore[i].size (), 1u);
    EXPECT_EQ (pasted.ignore[i].front (), cv::Rect (225, 50, 50, 300));  // the background's person, halved
    for (const cv::Rect &box : pasted.boxes[i])
    {
      ASSERT_EQ (box & cv::Rect (0, 0, canvas.cols, canvas.rows), box);
      // At most 15% off the asked range (people of one image vary a little).
      EXPECT_GE (box.height, 64 - 1);
      EXPECT_LE (box.height, 128 + 1);
      heights.insert (box.height);
      // The box is the bright block: bright inside (its edge pixel blended), dark round it.
      const cv::Rect inner (box.x + 2, box.y + 2, box.width - 4, box.height - 4);
      EXPECT_GT (cv::mean (canvas (inner))[0], 240) << box;
      EXPECT_NEAR (box.width * 2, box.height, 1) << box;
    }
  }
  EXPECT_GE (heights.size (), 4u);  // many sizes
  // Deterministic.
  const agex::PeopleImages again = agex::pasteCrops (backgrounds, {0, 1, 2, 3, 4, 5}, crops, {0, 2, 4}, params);
  for (std::size_t i = 0; i < pasted.images.size (); ++i)
    EXPECT_EQ (cv::norm (pasted.images[i], again.images[i], cv::NORM_INF), 0.0);
  params.min_height = 300;  // more than max_height
  EXPECT_THROW (agex::pasteCrops (backgrounds, {0}, crops, {0}, params), std::invalid_argument);
}

TEST (PastedCrops, FoldsSplitTheCrops)
{
  const std::vector<std::size_t> test = agex::foldIndices (12, 5, 1, true), train = agex::foldIndices (12, 5, 1, false);
  EXPECT_EQ (test, (std::vector<std::size_t>{1, 6, 11}));
  EXPECT_EQ (train.size (), 9u);
  for (const std::size_t i : test)
    EXPECT_EQ (std::count (train.begin (), train.end (), i), 0);
  EXPECT_EQ (agex::foldIndices (12, 5, -1, false).size (), 12u);
  EXPECT_TRUE (agex::foldIndices (12, 5, -1, true).empty ());
  EXPECT_THROW (agex::foldIndices (12, 1, 0, true), std::invalid_argument);
  EXPECT_THROW (agex::foldIndices (12, 5, 5, true), std::invalid_argument);
}

// INRIA cut several crops from one photo (crop001001a, crop001001c): they share a background
// and must fall in one fold, or a held-out crop's background was trained on.
TEST (PastedCrops, CropsOfOneSourcePhotoShareAFold)
{
  const std::vector<std::string> names{"crop001001a.png", "crop001001c.png", "crop001001e.png", "crop001002a.png",
                                       "person_044a.png", "person_044c.png", "x.png", "a.png", "b.png", "crop2.png"};
  const std::vector<std::size_t> photos = agex::cropSourcePhotos (names);
  EXPECT_EQ (photos, (std::vector<std::size_t>{0, 0, 0, 1, 2, 2, 3, 4, 5, 6}));
  const std::vector<std::size_t> test = agex::foldIndices (photos, 2, 0, true), train = agex::foldIndices (photos, 2, 0, false);
  EXPECT_EQ (test, (std::vector<std::size_t>{0, 1, 2, 4, 5, 7, 9}));
  EXPECT_EQ (train, (std::vector<std::size_t>{3, 6, 8}));
  EXPECT_THROW (agex::foldIndices (photos, 2, 2, true), std::invalid_argument);
}

TEST (PastedCrops, BadCropFoldersAreNamed)
{
  const fs::path dir = tempDir ("crops");
  EXPECT_THROW (agex::readPeopleCrops ((dir / "missing").string (), cv::Rect (16, 16, 64, 128)), std::runtime_error);
  try
  {
    agex::readPeopleCrops (dir.string (), cv::Rect (16, 16, 64, 128));
    ADD_FAILURE () << "an empty folder read as crops";
  }
  catch (const std::runtime_error &e)
  {
    EXPECT_NE (std::string (e.what ()).find (dir.string ()), std::string::npos) << e.what ();
  }
  ASSERT_TRUE (cv::imwrite ((dir / "a.png").string (), cv::Mat (160, 96, CV_8UC1, cv::Scalar (9))));
  EXPECT_EQ (agex::readPeopleCrops (dir.string (), cv::Rect (16, 16, 64, 128)).images.size (), 1u);
  EXPECT_THROW (agex::readPeopleCrops (dir.string (), cv::Rect (40, 40, 64, 128)), std::runtime_error);  // box outside
  ASSERT_TRUE (cv::imwrite ((dir / "b.png").string (), cv::Mat (100, 96, CV_8UC1, cv::Scalar (9))));
  try
  {
    agex::readPeopleCrops (dir.string (), cv::Rect (16, 16, 64, 128));
    ADD_FAILURE () << "crops of two sizes read";
  }
  catch (const std::runtime_error &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("b.png"), std::string::npos) << e.what ();
  }
  fs::remove_all (dir);
}

TEST (PastedCrops, TrainingWithoutAnyPeopleIsAClearError)
{
  std::vector<agex::AnnotatedImage> images{photoWithFigure (cv::Size (300, 300), cv::Point2f (150, 150), 1.0f, false)};
  agex::PeopleDetectorTraining training;
  training.paste_people = training.originals = false;
  training.backgrounds = true;  // backgrounds alone hold no person
  EXPECT_THROW (agex::trainPeopleDetector (images, {0}, training), std::runtime_error);
}

TEST (PastedCrops, InriaCropsInShared)
{
  const std::string folder = agex_test::sharedData ("people2d/inria_pos/images");
  AGEX_REQUIRE_SHARED_FILE (folder, "INRIA's person crops (../shared/data/people2d/inria_pos)");
  const agex::PeopleCrops crops = agex::readPeopleCrops (folder, cv::Rect (24, 32, 48, 96));
  EXPECT_EQ (crops.images.size (), 1208u);
  EXPECT_EQ (crops.images.front ().size (), cv::Size (96, 160));
  EXPECT_TRUE (std::is_sorted (crops.names.begin (), crops.names.end ()));
}
}  // namespace

// Person masks from annotation formats: COCO RLE (compressed strings and count lists, decoded
// against masks written out by hand, odd sizes, bad strings), label maps (a body split by an
// excluded label is joined again, without the excluded bulge) and instance masks.

#include <agex/landmarks/person_masks.h>

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <random>

namespace
{
cv::Mat
maskOf (const std::vector<std::string> &rows)
{
  cv::Mat mask (static_cast<int> (rows.size ()), static_cast<int> (rows[0].size ()), CV_8UC1, cv::Scalar (0));
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x)
      mask.at<unsigned char> (y, x) = rows[y][x] == '#' ? 255 : 0;
  return mask;
}

bool
same (const cv::Mat &a, const cv::Mat &b)
{
  return a.size () == b.size () && a.type () == b.type () && cv::countNonZero (a != b) == 0;
}

TEST (CocoRle, DecodesHandMadeMasksFromStringsAndLists)
{
  // 3 rows, 4 columns. Column-major: 0 0 1 | 1 1 1 | 1 0 0 | 0 0 1, i.e. runs of 2 unset, 5 set,
  // 4 unset, 1 set. In pycocotools' string: 2, 5, 4 as themselves ('2', '5', '4'), the fourth
  // count as its difference to the second, 1 - 5 = -4: one group 11100 (28, sign bit set) = 'L'.
  EXPECT_EQ (agex::cocoRleCountsFromString ("254L"), (std::vector<std::uint32_t>{2, 5, 4, 1}));
  const cv::Mat expected = maskOf ({".##.", ".#..", "##.#"});
  EXPECT_TRUE (same (agex::maskFromCocoRle ({2, 5, 4, 1}, 3, 4), expected));
  EXPECT_TRUE (same (agex::maskFromCocoRle (agex::cocoRleCountsFromString ("254L"), 3, 4), expected));

  // 7 x 5, the first pixel set: runs 0, 33, 2. 33 = 1 + 1 * 32 takes two groups: 1 with the
  // continuation bit (1 + 32 = 33, 'Q'), then 1 ('1').
  EXPECT_EQ (agex::cocoRleCountsFromString ("0Q12"), (std::vector<std::uint32_t>{0, 33, 2}));
  const cv::Mat seven_by_five = agex::maskFromCocoRle ({0, 33, 2}, 7, 5);
  ASSERT_EQ (seven_by_five.size (), cv::Size (5, 7));
  EXPECT_EQ (cv::countNonZero (seven_by_five), 33);
  EXPECT_EQ (cv::countNonZero (seven_by_five.colRange (0, 4)), 28);  // four full columns
  EXPECT_EQ (seven_by_five.at<unsigned char> (4, 4), 255);            // the last column to row 4
  EXPECT_EQ (seven_by_five.at<unsigned char> (5, 4), 0);
  EXPECT_EQ (seven_by_five.at<unsigned char> (6, 4), 0);

  EXPECT_EQ (agex::cocoRleString ({2, 5, 4, 1}), "254L");
  EXPECT_EQ (agex::cocoRleString ({0, 33, 2}), "0Q12");
}

TEST (CocoRle, EncodesAndDecodesRandomMasksOfOddSizes)
{
  std::mt19937 rng (7);
  for (const cv::Size size : {cv::Size (1, 1), cv::Size (3, 5), cv::Size (17, 9), cv::Size (101, 63)})
  {
    cv::Mat mask (size, CV_8UC1);
    cv::randu (mask, 0, 2);
    // Runs of all lengths: blobs as well as noise.
    cv::circle (mask, cv::Point (size.width / 2, size.height / 2), std::min (size.width, size.height) / 3, 1, cv::FILLED);
    mask = (mask != 0);
    const std::vector<std::uint32_t> counts = agex::cocoRleFromMask (mask);
    EXPECT_TRUE (same (agex::maskFromCocoRle (counts, size.height, size.width), mask)) << size;
    EXPECT_EQ (agex::cocoRleCountsFromString (agex::cocoRleString (counts)), counts) << size;
  }
  // Long runs and large differences between counts two apart (the sign handling).
  const std::vector<std::uint32_t> counts{70000, 3, 1, 123456, 5, 99999};
  EXPECT_EQ (agex::cocoRleCountsFromString (agex::cocoRleString (counts)), counts);
}

TEST (CocoRle, BadInputIsAClearError)
{
  auto message = [] (auto call) {
    try
    {
      call ();
    }
    catch (const std::invalid_argument &e)
    {
      return std::string (e.what ());
    }
    return std::string ("no error");
  };
  EXPECT_NE (message ([] { agex::maskFromCocoRle ({2, 5}, 3, 4); }).find ("add up to 7 pixels, not the 3 x 4 = 12"),
             std::string::npos);
  EXPECT_NE (message ([] { agex::maskFromCocoRle ({}, 0, 4); }).find ("positive"), std::string::npos);
  EXPECT_NE (message ([] { agex::cocoRleCountsFromString ("25 4"); }).find ("' ' at 2"), std::string::npos);
  EXPECT_NE (message ([] { agex::cocoRleCountsFromString ("2Q"); }).find ("ends inside a count"), std::string::npos);
  EXPECT_NE (message ([] { agex::cocoRleCountsFromString ("oooooooo1"); }).find ("too long"), std::string::npos);
  // A fourth count below zero: 'L' is -4 added to the second count, 1.
  EXPECT_NE (message ([] { agex::cocoRleCountsFromString ("214L"); }).find ("not a run length"), std::string::npos);
}

// A standing body (label 5, skin 41 for the head) with a bag (label 2) held across the waist:
// leaving the bag out cuts the body in two.
cv::Mat
bodyWithBag ()
{
  cv::Mat labels (60, 50, CV_8UC1, cv::Scalar (0));
  cv::rectangle (labels, cv::Rect (20, 12, 11, 44), 5, cv::FILLED);   // torso and legs
  cv::circle (labels, cv::Point (25, 7), 5, 41, cv::FILLED);          // head
  cv::rectangle (labels, cv::Rect (15, 28, 31, 6), 2, cv::FILLED);    // the bag, bulging to the right
  return labels;
}

TEST (LabelMap, BodySplitByAnExcludedLabelStaysInOnePiece)
{
  const cv::Mat labels = bodyWithBag ();
  const agex::LabelMapPerson person = agex::personFromLabelMap (labels, {2, 33, 56});
  ASSERT_TRUE (person.problem.empty ()) << person.problem;
  cv::Mat components;
  EXPECT_EQ (cv::connectedComponents (person.mask, components, 8), 2);  // background + one body
  EXPECT_GT (person.bridged_pixels, 0);
  EXPECT_FALSE (person.whole_excluded_region_kept);
  EXPECT_EQ (person.mask.at<unsigned char> (30, 25), 255);  // the bag in front of the body: body
  EXPECT_EQ (person.mask.at<unsigned char> (30, 40), 0);    // its bulge beside the body: not
  EXPECT_EQ (person.mask.at<unsigned char> (30, 16), 0);
  EXPECT_EQ (person.mask.at<unsigned char> (50, 25), 255);  // the legs below it
  EXPECT_EQ (person.mask.at<unsigned char> (7, 25), 255);   // the head (another label) is body

  // Without the exclusion the bag is body, bulge and all.
  const agex::LabelMapPerson with_bag = agex::personFromLabelMap (labels, {});
  EXPECT_EQ (with_bag.mask.at<unsigned char> (30, 40), 255);
  EXPECT_EQ (with_bag.bridged_pixels, 0);
}

TEST (LabelMap, PiecesTheExcludedLabelDidNotJoinAreLeftApart)
{
  cv::Mat labels = bodyWithBag ();
  cv::rectangle (labels, cv::Rect (2, 2, 4, 4), 19, cv::FILLED);  // a stray piece of "hair"
  const agex::LabelMapPerson person = agex::personFromLabelMap (labels, {2});
  cv::Mat components;
  EXPECT_EQ (cv::connectedComponents (person.mask, components, 8), 3);  // body + the stray piece
  EXPECT_EQ (person.mask.at<unsigned char> (3, 3), 255);
  // 16-bit label maps work alike.
  cv::Mat wide;
  bodyWithBag ().convertTo (wide, CV_16U);
  wide.setTo (1000, wide == 5);
  const agex::LabelMapPerson from_16_bit = agex::personFromLabelMap (wide, {2});
  EXPECT_EQ (cv::countNonZero (from_16_bit.mask != agex::personFromLabelMap (bodyWithBag (), {2}).mask), 0);
}

TEST (LabelMap, EmptyAndExcludedOnlyMasksSayWhy)
{
  EXPECT_NE (agex::personFromLabelMap (cv::Mat::zeros (8, 8, CV_8UC1), {2}).problem.find ("empty"), std::string::npos);
  EXPECT_NE (agex::personFromLabelMap (cv::Mat (8, 8, CV_8UC1, cv::Scalar (2)), {2}).problem.find ("only excluded"),
             std::string::npos);
  EXPECT_THROW (agex::personFromLabelMap (cv::Mat::zeros (8, 8, CV_8UC3), {}), std::invalid_argument);
  EXPECT_THROW (agex::personFromLabelMap (cv::Mat (), {}), std::invalid_argument);
}

TEST (InstanceMask, ValueKIsPersonK)
{
  cv::Mat instances (20, 30, CV_8UC1, cv::Scalar (0));
  cv::rectangle (instances, cv::Rect (2, 2, 5, 10), 1, cv::FILLED);
  cv::rectangle (instances, cv::Rect (20, 3, 6, 12), 3, cv::FILLED);
  const auto people = agex::peopleFromInstanceMask (instances);
  ASSERT_EQ (people.size (), 2u);
  EXPECT_EQ (people[0].first, 1);
  EXPECT_EQ (people[1].first, 3);
  EXPECT_EQ (cv::countNonZero (people[0].second), 50);
  EXPECT_EQ (cv::countNonZero (people[1].second), 72);
  EXPECT_EQ (people[1].second.at<unsigned char> (5, 22), 255);
  EXPECT_TRUE (agex::peopleFromInstanceMask (cv::Mat::zeros (4, 4, CV_16UC1)).empty ());
  EXPECT_THROW (agex::peopleFromInstanceMask (cv::Mat::zeros (4, 4, CV_32FC1)), std::invalid_argument);
}
}  // namespace

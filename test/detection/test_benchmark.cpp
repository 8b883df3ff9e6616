// The timings agex_bench reports, at library level: the summary of repeated timings, the
// depth pipeline with AGEX incremental against naive on the bundled frame, and the whole
// detector over frames (stages in order, "total" last, progress per frame, no frames refused).

#include "test_support.h"

#include <agex/detection/benchmark.h>
#include <agex/io/frame_io.h>

#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{
using namespace agex_test;

const std::string kFrame = AGEX_SOURCE_DIR "/data/frames/bonn_1_002.png";
const std::string kModel = AGEX_SOURCE_DIR "/data/models/agex_bonn_agex.yml";

TEST (Benchmark, TimingsSummariseToMeasuredSamples)
{
  const agex::TimingStats odd = agex::summariseTimings ({5.0, 1.0, 3.0, 2.0, 4.0});
  EXPECT_DOUBLE_EQ (odd.median, 3.0);
  EXPECT_DOUBLE_EQ (odd.p95, 5.0);
  const agex::TimingStats even = agex::summariseTimings ({1.0, 2.0});
  EXPECT_DOUBLE_EQ (even.median, 2.0) << "the upper middle sample, never a mean";
  EXPECT_DOUBLE_EQ (even.p95, 2.0);
  const agex::TimingStats none = agex::summariseTimings ({});
  EXPECT_DOUBLE_EQ (none.median, 0.0);
  EXPECT_DOUBLE_EQ (none.p95, 0.0);
}

TEST (Benchmark, DepthPipelineAndBothAgexModesOnTheBundledFrame)
{
  const agex::Frame frame = agex::loadFrame (kFrame);
  const agex::DepthPipelineBenchmark bench =
      agex::benchmarkDepthPipeline (frame.cloud, agex::DepthPipelineParams (), 5, 2);
  EXPECT_GE (bench.meshes, 1u);
  EXPECT_GT (bench.mesh_points, 0u);
  EXPECT_GT (bench.points, 0u);
  EXPECT_LE (bench.points, 5u * bench.meshes) << "AGEX_5: at most five points a mesh";
  EXPECT_TRUE (bench.identical) << "the incremental Dijkstra gives the naive reference's points";
  ASSERT_FALSE (bench.pipeline.empty ());
  EXPECT_EQ (bench.pipeline.back ().first, "total");
  EXPECT_GE (bench.agex_naive.p95, bench.agex_naive.median);
}

TEST (Benchmark, DetectorStagesOverFrames)
{
  EXPECT_THROW (agex::benchmarkDetector ({}, [] (agex::BodyPartDetector<pcl::PointXYZ> &) {}, 525.f, 525.f, 1),
                std::invalid_argument);
  AGEX_REQUIRE_SHARED_FILE (kModel, "the bundled AGEX model");
  const auto model = std::make_shared<const agex::DetectorModel> (agex::DetectorModel::load (kModel));
  const agex::DetectorSetup setup = [&] (agex::BodyPartDetector<pcl::PointXYZ> &detector) {
    detector.setModel (model);
  };
  const agex::Frame frame = agex::loadFrame (kFrame);
  const std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr> clouds{frame.cloud, frame.cloud};
  std::vector<std::size_t> steps;
  const agex::DetectorBenchmark bench = agex::benchmarkDetector (
      clouds, setup, 525.f, 525.f, 2, [&] (std::size_t done, std::size_t) { steps.push_back (done); });
  EXPECT_EQ (steps, (std::vector<std::size_t>{1, 2}));
  ASSERT_GE (bench.stages.size (), 2u);
  EXPECT_EQ (bench.stages.back ().first, "total");
  EXPECT_DOUBLE_EQ (bench.stages.back ().second.median, bench.total.median);
  EXPECT_GT (bench.total.median, 0.0);
  const auto one = agex::timeDetection (frame.cloud, setup, 525.f, 525.f);
  EXPECT_EQ (one.size (), bench.stages.size ());
}
// The memory run: samples at the interval and at the end, the first pass's figure taken after
// every frame ran once, and a detector in a steady stream that does not grow: frames 20 to 62
// of the same two clouds may not add 4 MiB (a leak of one 640x480 cloud, 4.7 MiB, per frame
// would add about 200 MiB; a leak under about 100 kB a frame would pass).
TEST (Benchmark, MemoryOfALongStream)
{
  EXPECT_THROW (agex::benchmarkMemory ({}, [] (agex::BodyPartDetector<pcl::PointXYZ> &) {}, 525.f, 525.f, 5, 1),
                std::invalid_argument);
  const agex::Frame frame = agex::loadFrame (kFrame);
  const std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr> one{frame.cloud};
  EXPECT_THROW (agex::benchmarkMemory (one, [] (agex::BodyPartDetector<pcl::PointXYZ> &) {}, 525.f, 525.f, 5, 0),
                std::invalid_argument);
  EXPECT_THROW (agex::benchmarkMemory (one, [] (agex::BodyPartDetector<pcl::PointXYZ> &) {}, 525.f, 525.f, 0, 1),
                std::invalid_argument);
  AGEX_REQUIRE_SHARED_FILE (kModel, "the bundled AGEX model");
  if (agex::residentBytes () == 0)
    GTEST_SKIP () << "no /proc/self/statm: resident memory cannot be read here";
  const auto model = std::make_shared<const agex::DetectorModel> (agex::DetectorModel::load (kModel));
  const agex::DetectorSetup setup = [&] (agex::BodyPartDetector<pcl::PointXYZ> &detector) {
    detector.setModel (model);
  };
  pcl::PointCloud<pcl::PointXYZ>::Ptr empty (new pcl::PointCloud<pcl::PointXYZ> (*frame.cloud));
  for (auto &p : *empty)
    p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN ();
  const std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr> clouds{frame.cloud, empty};
  std::vector<std::size_t> steps;
  const agex::MemoryBenchmark memory =
      agex::benchmarkMemory (clouds, setup, 525.f, 525.f, 62, 20, [&] (std::size_t done, std::size_t) { steps.push_back (done); });
  EXPECT_EQ (steps, (std::vector<std::size_t>{20, 40, 60, 62}));
  ASSERT_EQ (memory.samples.size (), 4u);
  EXPECT_EQ (memory.samples.back ().first, 62u);
  EXPECT_EQ (memory.final, memory.samples.back ().second);
  EXPECT_GT (memory.after_first_pass, 0u);
  EXPECT_GE (memory.peak, memory.final);
  EXPECT_GE (memory.peak, memory.after_first_pass);
  EXPECT_EQ (memory.growth (), static_cast<long long> (memory.final) - static_cast<long long> (memory.after_first_pass));
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP () << "AddressSanitizer holds freed memory back: resident memory grows without a leak";
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  GTEST_SKIP () << "AddressSanitizer holds freed memory back: resident memory grows without a leak";
#endif
#endif
  // From the 20th frame on (the allocator settled) to the 62nd.
  EXPECT_LT (static_cast<long long> (memory.final) - static_cast<long long> (memory.samples.front ().second), 4ll << 20)
      << "resident memory grew over a steady stream";
}
}  // namespace

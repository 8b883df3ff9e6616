#pragma once
// agex_bench's runs: the library's timings (agex/detection/benchmark.h) printed as a table and
// returned as the JSON report, and the detector's throughput on several threads.

#include <agex/apps/detector_flags.h>
#include <agex/apps/output_guard.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/io/frame_io.h>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** How agex_bench tells its own earlier report (of frames or of a dataset) by its keys. */
OutputRecogniser benchReportRecogniser ();

/** agex_bench INPUT...: per frame, full size and (portrait, 640x480 frames only) in the
  * 144x176 portrait view, AGEX_k incremental against naive and the pipeline stage by stage. */
nlohmann::json benchFrames (const std::vector<std::string> &inputs, const FrameOptions &frame_options,
                            const DepthPipelineParams &params, int k, int repeat, bool portrait);

/** agex_bench --dataset: the detector's stages over the selected frames on one thread (passes
  * runs per frame), then frames per second with jobs threads, every frame once; then, when
  * memory_frames > 0, the resident memory of one detector over that many frames
  * (agex::benchmarkMemory).
  * \throws std::runtime_error when no frame is selected */
nlohmann::json benchDataset (const std::string &spec, bool keyframes_only, const LoadedDetector &loaded, int passes,
                             int jobs, std::size_t memory_frames = 0);
}  // namespace apps
}  // namespace agex

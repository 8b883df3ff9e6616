// agex for Python (module agex._agex; doc/python.md): the detector, frames, AGEX interest
// points. Frames are processed without the GIL, so that a Python thread pool scales; each
// detect () call runs an agex::BodyPartDetector no other call is using, over the shared,
// read-only model (kept from call to call with its buffers).

#include <agex/classification/body_part_forest.h>
#include <agex/classification/model_error.h>
#include <agex/detection/body_part_detector.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/detection/detector_model.h>
#include <agex/io/dataset.h>
#include <agex/io/frame_io.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include <opencv2/core.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <dlfcn.h>

namespace py = pybind11;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{
// --- bundled data ---------------------------------------------------------------------

/** A file shipped with agex (relative to data/): the installed copy beside this module
  * (<prefix>/share/agex/<relative>, the module being in <prefix>/AGEX_PYTHON_INSTALL_DIR/agex),
  * else the source tree's, as the apps find theirs (apps/support bundledDataFile). */
std::string
bundledDataFile (const std::string &relative)
{
  Dl_info info{};
  std::error_code ec;
  if (::dladdr (reinterpret_cast<void *> (&bundledDataFile), &info) && info.dli_fname)
  {
    const auto installed = std::filesystem::path (info.dli_fname).parent_path () / AGEX_PYTHON_TO_PREFIX /
                           AGEX_INSTALL_DATADIR / "agex" / relative;
    if (std::filesystem::is_regular_file (installed, ec))
      return installed.lexically_normal ().string ();
  }
  return std::string (AGEX_SOURCE_DATA_DIR) + "/" + relative;
}

// --- conversions ----------------------------------------------------------------------

py::object
toPython (const nlohmann::json &j)
{
  switch (j.type ())
  {
  case nlohmann::json::value_t::null:
    return py::none ();
  case nlohmann::json::value_t::boolean:
    return py::bool_ (j.get<bool> ());
  case nlohmann::json::value_t::number_integer:
    return py::int_ (j.get<long long> ());
  case nlohmann::json::value_t::number_unsigned:
    return py::int_ (j.get<unsigned long long> ());
  case nlohmann::json::value_t::number_float:
    return py::float_ (j.get<double> ());
  case nlohmann::json::value_t::string:
    return py::str (j.get<std::string> ());
  case nlohmann::json::value_t::array:
  {
    py::list list;
    for (const auto &item : j)
      list.append (toPython (item));
    return std::move (list);
  }
  case nlohmann::json::value_t::object:
  {
    py::dict dict;
    for (const auto &[key, value] : j.items ())
      dict[py::str (key)] = toPython (value);
    return std::move (dict);
  }
  default:
    return py::none ();
  }
}

/** Nesting a setting may have: far more than any setting needs (a point is one list), and
  * far less than what exhausts the stack (a list that holds itself nests without end). */
constexpr int kMaxSettingDepth = 64;

/** Python's own value as JSON (settings given as keyword arguments).
  * \throws std::invalid_argument (ValueError) naming the setting: a value of another type,
  *         an int beyond 64 bits, a list nested deeper than kMaxSettingDepth */
nlohmann::json
toJson (const py::handle &o, const std::string &key, int depth = 0)
{
  if (py::isinstance<py::bool_> (o))
    return o.cast<bool> ();
  if (py::isinstance<py::int_> (o))
  {
    // Casting an int beyond 64 bits would throw pybind11's bare RuntimeError.
    const long long value = PyLong_AsLongLong (o.ptr ());
    if (value == -1 && PyErr_Occurred ())
    {
      PyErr_Clear ();
      throw std::invalid_argument (key + ": " + py::repr (o).cast<std::string> () +
                                   " does not fit a 64-bit integer");
    }
    return value;
  }
  if (py::isinstance<py::float_> (o))
    return o.cast<double> ();
  if (py::isinstance<py::str> (o))
    return o.cast<std::string> ();
  if (py::isinstance<py::sequence> (o))
  {
    if (depth >= kMaxSettingDepth)
      throw std::invalid_argument (key + ": lists nested more than " + std::to_string (kMaxSettingDepth) +
                                   " deep (or a list that contains itself)");
    nlohmann::json list = nlohmann::json::array ();
    for (const auto &item : o.cast<py::sequence> ())
      list.push_back (toJson (item, key, depth + 1));
    return list;
  }
  if (py::hasattr (o, "tolist"))  // a numpy array or scalar
  {
    if (depth >= kMaxSettingDepth)
      throw std::invalid_argument (key + ": nested more than " + std::to_string (kMaxSettingDepth) + " deep");
    return toJson (o.attr ("tolist") (), key, depth + 1);
  }
  throw std::invalid_argument (key + ": expected a number, a bool, a string or a list, got " +
                               py::str (py::type::handle_of (o)).cast<std::string> ());
}

/** A path as the C++ side reads it: one with a NUL would be read up to the NUL, another file. */
const std::string &
checkedPath (const char *name, const std::string &path)
{
  if (path.find ('\0') != std::string::npos)
    throw std::invalid_argument (std::string (name) + ": the path contains a NUL character: " +
                                 py::repr (py::str (path)).cast<std::string> ());
  return path;
}

py::dict
detectionDict (const agex::BodyPartDetection &d)
{
  return toPython (agex::toJson (d));  // the same fields as agex_detect's JSON
}

py::dict
interestPointDict (const agex::InterestPoint &p)
{
  py::dict d;
  d["position"] = py::make_tuple (p.x, p.y, p.z);
  d["orientation"] = py::make_tuple (p.orientation[0], p.orientation[1], p.orientation[2]);
  d["pixel"] = py::make_tuple (p.u, p.v);
  d["rank"] = p.rank;
  d["mesh"] = p.mesh;
  d["geodesic_distance"] = p.geodesic_distance;
  return d;
}

/** The point with its pixel at the input's resolution (DepthPipelineParams::working_spacing). */
agex::InterestPoint
atInputPixel (agex::InterestPoint p, const agex::DepthPipelineResult &r)
{
  if (r.stride > 1 && r.filtered)
  {
    const Eigen::Vector2i pixel = r.inputPixel (p.v * static_cast<int> (r.filtered->width) + p.u);
    p.u = pixel.x ();
    p.v = pixel.y ();
  }
  return p;
}

/** An h x w array (the input's size) of a value per working pixel of r, fill where none. */
template <typename T, typename F>
py::array_t<T>
inputImage (const agex::DepthPipelineResult &r, py::ssize_t h, py::ssize_t w, T fill, F value)
{
  py::array_t<T> image ({h, w});
  T *out = image.mutable_data ();
  for (py::ssize_t v = 0; v < h; ++v)
    for (py::ssize_t u = 0; u < w; ++u)
    {
      const int i = r.workingIndex (static_cast<int> (u), static_cast<int> (v));
      out[v * w + u] = i < 0 ? fill : value (i);
    }
  return image;
}

/** An H x W array of one float field of an organized cloud (a copy). */
template <typename PointT, typename F>
py::array_t<float>
fieldImage (const pcl::PointCloud<PointT> &cloud, F field)
{
  py::array_t<float> image ({static_cast<py::ssize_t> (cloud.height), static_cast<py::ssize_t> (cloud.width)});
  auto out = image.template mutable_unchecked<2> ();
  for (std::uint32_t v = 0; v < cloud.height; ++v)
    for (std::uint32_t u = 0; u < cloud.width; ++u)
      out (v, u) = field (cloud (u, v));
  return image;
}

// --- frames ---------------------------------------------------------------------------

/** A frame: the organized cloud the detector sees, and how it was made. */
struct PyFrame
{
  agex::Frame frame;
  bool has_intrinsics () const { return frame.from_depth_image; }
  int width () const { return static_cast<int> (frame.cloud->width); }
  int height () const { return static_cast<int> (frame.cloud->height); }
};

/** A read-only view into the frame's cloud: its z (H x W), or its x, y, z (H x W x 3). */
py::array
cloudView (const std::shared_ptr<PyFrame> &self, bool xyz)
{
  const Cloud &cloud = *self->frame.cloud;
  const auto point = static_cast<py::ssize_t> (sizeof (pcl::PointXYZ));
  const auto row = point * static_cast<py::ssize_t> (cloud.width);
  // The view keeps the frame alive.
  py::capsule owner (new std::shared_ptr<PyFrame> (self),
                     [] (void *p) { delete static_cast<std::shared_ptr<PyFrame> *> (p); });
  py::array view =
      xyz ? py::array (py::dtype::of<float> (), {static_cast<py::ssize_t> (cloud.height), static_cast<py::ssize_t> (cloud.width), py::ssize_t (3)},
                       {row, point, static_cast<py::ssize_t> (sizeof (float))}, &cloud.points[0].x, owner)
          : py::array (py::dtype::of<float> (), {static_cast<py::ssize_t> (cloud.height), static_cast<py::ssize_t> (cloud.width)},
                       {row, point}, &cloud.points[0].z, owner);
  view.attr ("setflags") (py::arg ("write") = false);
  return view;
}

std::string
shapeText (const py::array &a)
{
  std::ostringstream text;
  text << "(";
  for (py::ssize_t i = 0; i < a.ndim (); ++i)
    text << (i ? ", " : "") << a.shape (i);
  text << (a.ndim () == 1 ? ",)" : ")");
  return text.str ();
}

/** Refuses an intrinsic or depth scale as the apps' flags do (agex::intrinsicProblem), naming it. */
void
checkIntrinsic (const char *name, agex::IntrinsicKind kind, double value)
{
  const std::string problem = agex::intrinsicProblem (kind, value);
  if (!problem.empty ())
    throw std::invalid_argument (std::string (name) + " " + problem);
}

/** \brief A frame from a depth array: uint16 (default millimetres), float32 (default metres)
  * or uint8 (depth_scale required), read in place when its rows are contiguous, else copied.
  * The back-projection runs without the GIL.
  * \throws std::invalid_argument (ValueError) naming what is wrong with the array or the intrinsics */
std::shared_ptr<PyFrame>
frameFromArray (const py::array &input, double fx, double fy, double cx, double cy, std::optional<double> depth_scale)
{
  py::array depth = input;
  // A masked array's masked pixels are invalid depth (0 in every dtype), not the data under the mask.
  const py::module_ ma = py::module_::import ("numpy.ma");
  if (py::isinstance (input, ma.attr ("MaskedArray")))
    depth = py::array (ma.attr ("filled") (input, 0));
  int type = -1;
  double default_scale = 0.0;
  if (depth.dtype ().is (py::dtype::of<std::uint16_t> ()))
    type = CV_16U, default_scale = 0.001;
  else if (depth.dtype ().is (py::dtype::of<float> ()))
    type = CV_32F, default_scale = 1.0;
  else if (depth.dtype ().is (py::dtype::of<std::uint8_t> ()))
    type = CV_8U;
  else
    throw std::invalid_argument ("depth must be a numpy array of uint16 (millimetres by default), float32 (metres by "
                                 "default) or uint8 (with depth_scale), in native byte order; got dtype " +
                                 py::str (depth.dtype ()).cast<std::string> () +
                                 " (convert with depth.astype(numpy.float32) or numpy.uint16)");
  if (depth.ndim () != 2)
    throw std::invalid_argument ("depth must be a 2-D array (rows x columns); got a " + std::to_string (depth.ndim ()) +
                                 "-D array of shape " + shapeText (depth) +
                                 (depth.ndim () == 3 ? " (for one channel of an image, pass depth[..., 0])" : ""));
  if (depth.shape (0) < 2 || depth.shape (1) < 2)
    throw std::invalid_argument ("depth of shape " + shapeText (depth) +
                                 " is too small: a depth frame needs at least 2 rows and 2 columns");
  if (static_cast<std::uint64_t> (depth.shape (0)) * static_cast<std::uint64_t> (depth.shape (1)) > agex::kMaxFramePixels)
    throw std::invalid_argument ("depth of shape " + shapeText (depth) + " has more than the " +
                                 std::to_string (agex::kMaxFramePixels) + " pixels agex reads");
  const double scale = depth_scale ? *depth_scale : default_scale;
  if (type == CV_8U && !depth_scale)
    throw std::invalid_argument ("uint8 depth needs depth_scale (metres per unit); 8-bit depth has no common unit");
  checkIntrinsic ("depth_scale", agex::IntrinsicKind::kDepthScale, scale);
  checkIntrinsic ("fx", agex::IntrinsicKind::kFocalLength, fx);
  checkIntrinsic ("fy", agex::IntrinsicKind::kFocalLength, fy);
  const auto rows = depth.shape (0), cols = depth.shape (1);
  if (!(cx >= -0.5 && cx <= cols - 0.5) || !(cy >= -0.5 && cy <= rows - 0.5))
  {
    std::ostringstream text;
    text << "the principal point (cx " << cx << ", cy " << cy << ") lies outside the " << cols << "x" << rows
         << " image; check cx and cy";
    throw std::invalid_argument (text.str ());
  }
  // Rows of contiguous pixels are read in place, whatever the row step; anything else is copied once.
  const auto item = depth.itemsize ();
  if (!(depth.strides (1) == item && depth.strides (0) >= cols * item && depth.strides (0) % item == 0 &&
        reinterpret_cast<std::uintptr_t> (depth.data ()) % static_cast<std::uintptr_t> (item) == 0))
    // A fresh C-order copy: ensure (c_style) would hand back an unaligned array unchanged.
    depth = py::array (depth.attr ("copy") ("C"));
  const cv::Mat image (static_cast<int> (rows), static_cast<int> (cols), type, const_cast<void *> (depth.data ()),
                       static_cast<std::size_t> (depth.strides (0)));
  auto result = std::make_shared<PyFrame> ();
  agex::Frame &frame = result->frame;
  frame.path = "<array>";
  frame.intrinsics = {fx, fy, cx, cy};
  frame.depth_scale = scale;
  frame.from_depth_image = true;
  frame.cloud.reset (new Cloud);
  {
    py::gil_scoped_release release;
    agex::depthImageToCloud (image, frame.intrinsics, scale, *frame.cloud);
  }
  return result;
}

std::shared_ptr<PyFrame>
loadFrame (const std::string &path, std::optional<double> fx, std::optional<double> fy, std::optional<double> cx,
           std::optional<double> cy, std::optional<double> depth_scale, int width, int height)
{
  agex::FrameOptions options;
  // As the apps' --fx ... --cy: intrinsics given are meant for the frame at hand, whatever its size.
  using agex::IntrinsicKind;
  for (const auto &[name, value, field, kind] :
       {std::make_tuple ("fx", fx, &agex::CameraIntrinsics::fx, IntrinsicKind::kFocalLength),
        std::make_tuple ("fy", fy, &agex::CameraIntrinsics::fy, IntrinsicKind::kFocalLength),
        std::make_tuple ("cx", cx, &agex::CameraIntrinsics::cx, IntrinsicKind::kPrincipalPoint),
        std::make_tuple ("cy", cy, &agex::CameraIntrinsics::cy, IntrinsicKind::kPrincipalPoint)})
    if (value)
    {
      checkIntrinsic (name, kind, *value);
      options.intrinsics.*field = *value;
      options.intrinsics_width = options.intrinsics_height = 0;
    }
  if (depth_scale)
    checkIntrinsic ("depth_scale", IntrinsicKind::kDepthScale, *depth_scale);
  options.depth_scale = depth_scale.value_or (0.0);
  options.width = width;
  options.height = height;
  checkedPath ("path", path);
  auto result = std::make_shared<PyFrame> ();
  py::gil_scoped_release release;
  result->frame = agex::loadFrame (path, options);
  return result;
}

/** A frame from detect ()'s arguments: a Frame, or an array and its intrinsics. */
std::shared_ptr<PyFrame>
frameOf (const py::object &depth, std::optional<double> fx, std::optional<double> fy, std::optional<double> cx,
         std::optional<double> cy, std::optional<double> depth_scale)
{
  if (py::isinstance<PyFrame> (depth))
  {
    if (fx || fy || cx || cy || depth_scale)
      throw std::invalid_argument ("a Frame carries its intrinsics and depth scale: give none with it");
    return depth.cast<std::shared_ptr<PyFrame>> ();
  }
  if (!py::isinstance<py::array> (depth))
    throw std::invalid_argument ("depth must be an agex.Frame or a 2-D numpy array; got " +
                                 py::str (py::type::handle_of (depth)).cast<std::string> ());
  if (!fx || !fy || !cx || !cy)
    throw std::invalid_argument ("a depth array needs its camera's fx, fy, cx and cy (pixels)");
  return frameFromArray (depth.cast<py::array> (), *fx, *fy, *cx, *cy, depth_scale);
}

// --- the detector ---------------------------------------------------------------------

class PyDetector
{
public:
  PyDetector (std::optional<std::string> model, std::optional<std::string> forest, std::optional<std::string> mode,
              int forest_stride, float cascade_min_confidence, float cascade_miss_rate, float tip_radius,
              float tip_min_confidence, std::optional<std::string> window_model, std::optional<float> window_weight)
  {
    const std::string model_path = model ? checkedPath ("model", *model) : bundledDataFile ("models/agex_bonn.yml");
    if (forest)
      checkedPath ("forest", *forest);
    if (mode && *mode != "model" && *mode != "forest")
      throw std::invalid_argument ("mode must be 'model' (the model's classifier) or 'forest' (the forest's part "
                                   "modes alone); got '" + *mode + "'");
    if (forest_stride < 0 || forest_stride > 8)
      throw std::invalid_argument ("forest_stride must lie in [0, 8] (0: by the focal length)");
    mode_ = mode && *mode == "forest" ? agex::DetectorMode::Forest : agex::DetectorMode::Model;
    forest_stride_ = forest_stride;
    if (!(cascade_min_confidence >= 0.f && cascade_min_confidence < 1.f))
      throw std::invalid_argument ("cascade_min_confidence must lie in [0, 1) (0: every candidate classified in full)");
    if (!(cascade_miss_rate >= 0.f && cascade_miss_rate <= 0.5f))
      throw std::invalid_argument ("cascade_miss_rate must lie in [0, 0.5]");
    cascade_min_confidence_ = cascade_min_confidence;
    cascade_miss_rate_ = cascade_miss_rate;
    tip_refinement_.radius = tip_radius;
    tip_refinement_.min_relative_confidence = tip_min_confidence;
    tip_refinement_.validate ([] (const std::string &key) {
      return std::string (key == "radius" ? "tip_radius" : "tip_min_confidence");
    });
    // Checked while the GIL is held: a bad path's message is built from Python objects.
    const std::string window_model_path = window_model ? checkedPath ("window_model", *window_model) : std::string ();
    if (window_weight && !(*window_weight >= 0.f && *window_weight <= 1.f))
      throw std::invalid_argument ("window_weight must lie in [0, 1] (0: off)");
    py::gil_scoped_release release;
    model_ = std::make_shared<const agex::DetectorModel> (agex::DetectorModel::load (model_path));
    model_path_ = model_path;
    std::string forest_path = forest ? *forest : std::string ();
    if (forest_path.empty () && model_->settings ().kind == agex::DetectorKind::Fused)
      forest_path = model_->forestPath ();  // a fused model's own forest
    if (mode_ == agex::DetectorMode::Forest && forest_path.empty ())
      throw std::invalid_argument ("mode 'forest' needs a forest (a forest file or a directory of PCL trees)");
    if (!forest_path.empty ())
      forest_ = agex::BodyPartForest::load (forest_path);
    forest_path_ = forest_path;
    // As agex_detect's --window-model and --window-weight: a fused model's own by default.
    const agex::WindowChoice window = agex::chooseWindowModel (
        *model_, model_path, model_->settings ().kind == agex::DetectorKind::Fused && mode_ == agex::DetectorMode::Model,
        window_model_path, window_weight ? *window_weight : -1.f,
        agex::BodyPartDetector<pcl::PointXYZ>::kDefaultWindowWeight, "window_model", "window_weight");
    if (!window.path.empty ())
    {
      window_model_ = agex::loadWindowModel (window.path, *model_, window.own ? model_path : std::string ());
      window_weight_ = window.weight;
      window_path_ = window.path;
    }
  }

  /** Detections of one frame; the intermediate results are kept for intermediate (). */
  py::object detect (const py::object &depth, std::optional<double> fx, std::optional<double> fy,
                     std::optional<double> cx, std::optional<double> cy, std::optional<double> depth_scale,
                     bool return_intermediate)
  {
    const std::shared_ptr<PyFrame> frame = frameOf (depth, fx, fy, cx, cy, depth_scale);
    std::shared_ptr<agex::BodyPartDetector<pcl::PointXYZ>> detector;
    std::vector<agex::BodyPartDetection> detections;
    {
      py::gil_scoped_release release;
      detector = takeDetector ();
      detector->setModel (model_);
      detector->setForest (forest_);
      detector->setMode (mode_);
      detector->setForestStride (forest_stride_);
      detector->setCascadeMinConfidence (cascade_min_confidence_);
      detector->setCascadeMissRate (cascade_miss_rate_);
      detector->setTipRefinement (tip_refinement_);
      detector->setWindowRescoring (window_model_, window_weight_);
      // A PCD carries no intrinsics: the detector estimates them (0), whatever the last frame had.
      if (frame->has_intrinsics ())
        detector->setFocalLength (static_cast<float> (frame->frame.intrinsics.fx),
                                  static_cast<float> (frame->frame.intrinsics.fy));
      else
        detector->setFocalLength (0.f, 0.f);
      detector->setInputCloud (frame->frame.cloud);
      detector->compute (detections);
    }
    {
      std::lock_guard<std::mutex> lock (mutex_);
      if (last_)
        idle_.push_back (std::move (last_));  // reused once intermediate () no longer reads it
      last_ = detector;
    }
    py::list list;
    for (const auto &d : detections)
      list.append (detectionDict (d));
    if (return_intermediate)
      return py::make_tuple (list, intermediateOf (*detector));
    return std::move (list);
  }

  /** A C++ detector for one detect () call: an idle one that nothing else holds (kept from
    * earlier frames with its buffers, agex::DepthPipeline), else a new one. The last call's
    * detector is not idle: intermediate () reads it. */
  std::shared_ptr<agex::BodyPartDetector<pcl::PointXYZ>> takeDetector ()
  {
    std::lock_guard<std::mutex> lock (mutex_);
    for (auto it = idle_.begin (); it != idle_.end (); ++it)
      if (it->use_count () == 1)
      {
        auto detector = std::move (*it);
        idle_.erase (it);
        return detector;
      }
    return std::make_shared<agex::BodyPartDetector<pcl::PointXYZ>> ();
  }

  py::dict intermediate () const
  {
    std::shared_ptr<const agex::BodyPartDetector<pcl::PointXYZ>> last;
    {
      std::lock_guard<std::mutex> lock (mutex_);
      last = last_;
    }
    if (!last)
      throw std::runtime_error ("intermediate () comes after a detect ()");
    return intermediateOf (*last);
  }

  const std::string &modelPath () const { return model_path_; }
  const std::string &forestPath () const { return forest_path_; }
  const std::string &windowPath () const { return window_path_; }
  float windowWeight () const { return window_model_ ? window_weight_ : 0.f; }
  std::string mode () const { return agex::detectorModeName (mode_); }
  std::string kind () const { return agex::detectorKindName (model_->settings ().kind); }

  static py::dict intermediateOf (const agex::BodyPartDetector<pcl::PointXYZ> &detector)
  {
    const agex::DepthPipelineResult &r = detector.getIntermediate ();
    const auto input = detector.getInputCloud ();
    const py::ssize_t h = input ? input->height : 0, w = input ? input->width : 0;
    py::dict d;
    const float nan = std::numeric_limits<float>::quiet_NaN ();
    // Every image at the input's size: with a working density each working pixel fills its
    // stride x stride block (DepthPipelineResult::workingIndex).
    if (r.filtered && r.filtered->isOrganized ())
      d["filtered_depth"] = inputImage<float> (r, h, w, nan, [&r] (int i) { return (*r.filtered)[static_cast<std::size_t> (i)].z; });
    else
    {
      py::array_t<float> empty ({h, w});
      std::fill (empty.mutable_data (), empty.mutable_data () + h * w, nan);
      d["filtered_depth"] = empty;
    }
    std::vector<std::int32_t> mesh_of (r.filtered ? r.filtered->size () : 0, -1);
    for (std::size_t m = 0; m < r.meshes.size (); ++m)
      for (const int index : r.meshes[m].indices)
        if (index >= 0 && static_cast<std::size_t> (index) < mesh_of.size ())
          mesh_of[static_cast<std::size_t> (index)] = static_cast<std::int32_t> (m);
    d["mesh_ids"] = inputImage<std::int32_t> (r, h, w, -1, [&mesh_of] (int i) { return mesh_of[static_cast<std::size_t> (i)]; });
    const auto &labels = detector.getPartLabels ();
    py::array_t<std::int32_t> parts ({h, w});
    std::fill (parts.mutable_data (), parts.mutable_data () + h * w, -1);
    py::array_t<float> probabilities ({h, w, py::ssize_t (4)});
    std::fill (probabilities.mutable_data (), probabilities.mutable_data () + h * w * 4, nan);
    if (r.filtered && labels.width == r.filtered->width && labels.height == r.filtered->height)
      for (py::ssize_t v = 0; v < h; ++v)
        for (py::ssize_t u = 0; u < w; ++u)
        {
          const int j = r.workingIndex (static_cast<int> (u), static_cast<int> (v));
          if (j < 0)
            continue;
          const auto &l = labels[static_cast<std::size_t> (j)];
          const py::ssize_t i = v * w + u;
          parts.mutable_data ()[i] = l.label;
          for (int p = 0; p < 4; ++p)
            probabilities.mutable_data ()[i * 4 + p] = l.probability (p);
        }
    d["part_labels"] = parts;
    d["part_probabilities"] = probabilities;
    py::list points;
    for (const auto &p : r.interest_points)
      points.append (interestPointDict (atInputPixel (p, r)));
    d["interest_points"] = points;
    py::list modes;
    for (const auto &m : detector.getPartModes ())
    {
      py::dict mode;
      mode["part"] = agex::labelPartName (m.part);
      mode["position"] = py::make_tuple (m.position.x (), m.position.y (), m.position.z ());
      mode["tip"] = py::make_tuple (m.tip.x (), m.tip.y (), m.tip.z ());
      mode["direction"] = py::make_tuple (m.direction.x (), m.direction.y (), m.direction.z ());
      mode["confidence"] = m.confidence;
      mode["mass"] = m.mass;
      modes.append (mode);
    }
    d["part_modes"] = modes;
    d["floor_plane"] = r.floor_found ? py::object (py::make_tuple (r.floor_plane[0], r.floor_plane[1], r.floor_plane[2],
                                                                   r.floor_plane[3]))
                                     : py::object (py::none ());
    py::dict ms;
    for (const auto &[stage, value] : r.ms)
      ms[py::str (stage)] = value;
    d["ms"] = ms;
    return d;
  }

private:
  agex::DetectorModel::ConstPtr model_;
  agex::BodyPartForest::ConstPtr forest_;
  agex::DetectorMode mode_ = agex::DetectorMode::Model;
  int forest_stride_ = 1;
  float cascade_min_confidence_ = agex::BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMinConfidence;
  float cascade_miss_rate_ = agex::BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMissRate;
  agex::TipRefinementParams tip_refinement_;
  agex::DetectorModel::ConstPtr window_model_;
  float window_weight_ = 0.f;
  std::string model_path_, forest_path_, window_path_;
  mutable std::mutex mutex_;
  std::shared_ptr<agex::BodyPartDetector<pcl::PointXYZ>> last_;
  // Detectors of earlier calls, at most one per call that ran at the same time as others.
  std::vector<std::shared_ptr<agex::BodyPartDetector<pcl::PointXYZ>>> idle_;
};

// --- AGEX interest points -------------------------------------------------------------

py::object
agexKeypoints (const py::object &depth, std::optional<double> fx, std::optional<double> fy, std::optional<double> cx,
               std::optional<double> cy, std::optional<double> depth_scale, std::optional<std::string> model,
               bool return_intermediate, const py::kwargs &settings)
{
  const std::shared_ptr<PyFrame> frame = frameOf (depth, fx, fy, cx, cy, depth_scale);
  // The settings: a model's pipeline, or the documented defaults; keyword arguments override
  // them by their model-file keys, and all are range-checked as model files are.
  agex::DepthPipelineParams params;
  if (model)
  {
    checkedPath ("model", *model);
    py::gil_scoped_release release;
    params = agex::DetectorModel::load (*model).settings ().pipeline;
  }
  nlohmann::json doc = params.toJson ();
  for (const auto &[key, value] : settings)
  {
    const std::string name = py::str (key).cast<std::string> ();
    if (name == "naive")
    {
      const nlohmann::json naive = toJson (value, name);
      if (!naive.is_boolean ())
        throw std::invalid_argument ("naive: expected True or False, got " + py::repr (value).cast<std::string> ());
      params.naive = naive.get<bool> ();
    }
    else if (!doc.contains (name))
    {
      std::string keys;
      for (const auto &[k, v] : doc.items ())
        keys += (keys.empty () ? "" : ", ") + k;
      throw std::invalid_argument ("unknown setting '" + name + "' (settings: " + keys + ", naive)");
    }
    else
      doc[name] = toJson (value, name);
  }
  const bool naive = params.naive;
  params = agex::DepthPipelineParams::fromJson (doc, "agex_keypoints");
  params.naive = naive;
  agex::DepthPipelineResult result;
  {
    py::gil_scoped_release release;
    result = agex::runDepthPipeline (frame->frame.cloud, params);
  }
  py::list points;
  for (const auto &p : result.interest_points)
    points.append (interestPointDict (atInputPixel (p, result)));
  if (!return_intermediate)
    return std::move (points);
  py::dict d;
  const Cloud &input = *frame->frame.cloud;
  const py::ssize_t h = input.height, w = input.width;
  // At the input's size, as intermediate () gives them (a working pixel fills its block).
  std::vector<std::int32_t> mesh_of (result.filtered ? result.filtered->size () : 0, -1);
  for (std::size_t m = 0; m < result.meshes.size (); ++m)
    for (const int index : result.meshes[m].indices)
      if (index >= 0 && static_cast<std::size_t> (index) < mesh_of.size ())
        mesh_of[static_cast<std::size_t> (index)] = static_cast<std::int32_t> (m);
  d["filtered_depth"] =
      result.filtered ? py::object (inputImage<float> (result, h, w, std::numeric_limits<float>::quiet_NaN (),
                                                       [&result] (int i) { return (*result.filtered)[static_cast<std::size_t> (i)].z; }))
                      : py::object (py::none ());
  d["mesh_ids"] = inputImage<std::int32_t> (result, h, w, -1, [&mesh_of] (int i) { return mesh_of[static_cast<std::size_t> (i)]; });
  py::dict ms;
  for (const auto &[stage, value] : result.ms)
    ms[py::str (stage)] = value;
  d["ms"] = ms;
  return py::make_tuple (points, d);
}
}  // namespace

PYBIND11_MODULE (_agex, m)
{
  m.doc () = "agex: heads, hands and feet in depth frames (doc/python.md)";
  // Messages are the apps' (what follows "agex_detect: error: ").
  py::register_exception<agex::FrameError> (m, "FrameError", PyExc_RuntimeError);
  py::register_exception<agex::ModelError> (m, "ModelError", PyExc_RuntimeError);
  py::register_exception<agex::DatasetError> (m, "DatasetError", PyExc_RuntimeError);

  py::class_<PyFrame, std::shared_ptr<PyFrame>> (m, "Frame",
                                                 "An organized depth frame: what the detector sees (metres, NaN = invalid)")
    .def (py::init ([] (const py::array &depth, double fx, double fy, double cx, double cy,
                        std::optional<double> depth_scale) { return frameFromArray (depth, fx, fy, cx, cy, depth_scale); }),
          py::arg ("depth"), py::arg ("fx"), py::arg ("fy"), py::arg ("cx"), py::arg ("cy"),
          py::arg ("depth_scale") = py::none (),
          "A frame from a 2-D depth array: uint16 (millimetres unless depth_scale says otherwise), float32 (metres "
          "unless ...) or uint8 (depth_scale needed); 0 (and for floats NaN, inf, negative) is invalid")
    .def_property_readonly ("depth", [] (const std::shared_ptr<PyFrame> &f) { return cloudView (f, false); },
                            "H x W float32 depth in metres, NaN where invalid (a read-only view)")
    .def_property_readonly ("points", [] (const std::shared_ptr<PyFrame> &f) { return cloudView (f, true); },
                            "H x W x 3 float32 x, y, z in metres (a read-only view)")
    .def_property_readonly ("width", &PyFrame::width)
    .def_property_readonly ("height", &PyFrame::height)
    .def_property_readonly ("path", [] (const PyFrame &f) { return f.frame.path; })
    .def_property_readonly ("has_intrinsics", &PyFrame::has_intrinsics,
                            "False for PCD frames: they carry points, no camera (the detector estimates the focal length)")
    .def_property_readonly ("fx", [] (const PyFrame &f) { return f.frame.intrinsics.fx; })
    .def_property_readonly ("fy", [] (const PyFrame &f) { return f.frame.intrinsics.fy; })
    .def_property_readonly ("cx", [] (const PyFrame &f) { return f.frame.intrinsics.cx; })
    .def_property_readonly ("cy", [] (const PyFrame &f) { return f.frame.intrinsics.cy; })
    .def_property_readonly ("depth_scale", [] (const PyFrame &f) { return f.frame.depth_scale; })
    .def ("__repr__", [] (const PyFrame &f) {
      std::ostringstream text;
      text << "<agex.Frame " << f.frame.path << " " << f.width () << "x" << f.height () << ">";
      return text.str ();
    });

  m.def ("load_frame", &loadFrame, py::arg ("path"), py::arg ("fx") = py::none (), py::arg ("fy") = py::none (),
         py::arg ("cx") = py::none (), py::arg ("cy") = py::none (), py::arg ("depth_scale") = py::none (),
         py::arg ("width") = 640, py::arg ("height") = 480,
         "Loads a .pcd, .png (8 or 16-bit) or .u16 frame as agex_detect does (agex::loadFrame): without fx, fy, cx, cy, "
         "depth images must be 640x480 (the Kinect's intrinsics); width and height are a raw .u16 frame's size");

  py::class_<PyDetector> (m, "BodyPartDetector", "Heads, hands and feet: agex::BodyPartDetector")
    .def (py::init<std::optional<std::string>, std::optional<std::string>, std::optional<std::string>, int, float,
                   float, float, float, std::optional<std::string>, std::optional<float>> (),
          py::arg ("model") = py::none (), py::arg ("forest") = py::none (), py::arg ("mode") = py::none (),
          py::arg ("forest_stride") = 1,
          py::arg ("cascade_min_confidence") = agex::BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMinConfidence,
          py::arg ("cascade_miss_rate") = agex::BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMissRate,
          py::arg ("tip_radius") = agex::TipRefinementParams ().radius,
          py::arg ("tip_min_confidence") = agex::TipRefinementParams ().min_relative_confidence,
          py::arg ("window_model") = py::none (), py::arg ("window_weight") = py::none (),
          "model: a model file (default: the bundled agex_bonn.yml); forest: a body-part forest (an agex forest file, "
          "a PCL tree file or a directory of them); mode: 'model' (default) or 'forest' (the forest's part modes "
          "alone); forest_stride: one evaluated pixel per stride x stride cell; cascade_min_confidence, "
          "cascade_miss_rate: the classifier's soft cascade, as agex_detect's flags (0: every candidate in full); "
          "tip_radius, tip_min_confidence: fused hands and feet moved to their part's extremity, as agex_detect's "
          "--tip-radius and --tip-min-confidence (0: off); window_model, window_weight: a sliding-window model's "
          "confidences blended into a fused model's candidates, as --window-model and --window-weight (default: the "
          "fused model's own; weight 0: off)")
    .def ("detect", &PyDetector::detect, py::arg ("depth"), py::arg ("fx") = py::none (), py::arg ("fy") = py::none (),
          py::arg ("cx") = py::none (), py::arg ("cy") = py::none (), py::arg ("depth_scale") = py::none (),
          py::kw_only (), py::arg ("return_intermediate") = false,
          "Detections of one frame (an agex.Frame, or a depth array with fx, fy, cx, cy), most confident first: dicts "
          "with the fields of agex_detect's JSON. With return_intermediate, (detections, intermediate).")
    .def ("intermediate", &PyDetector::intermediate,
          "What the last detect () on this object saw: filtered_depth, mesh_ids and part_labels (H x W, -1 = none), "
          "part_probabilities, interest_points, part_modes, floor_plane, ms")
    .def_property_readonly ("model", &PyDetector::modelPath)
    .def_property_readonly ("forest", &PyDetector::forestPath)
    .def_property_readonly ("window_model", &PyDetector::windowPath)
    .def_property_readonly ("window_weight", &PyDetector::windowWeight)
    .def_property_readonly ("mode", &PyDetector::mode)
    .def_property_readonly ("kind", &PyDetector::kind, "the model's detector kind: agex, sliding_window or fused");

  m.def ("agex_keypoints", &agexKeypoints, py::arg ("depth"), py::arg ("fx") = py::none (), py::arg ("fy") = py::none (),
         py::arg ("cx") = py::none (), py::arg ("cy") = py::none (), py::arg ("depth_scale") = py::none (),
         py::kw_only (), py::arg ("model") = py::none (), py::arg ("return_intermediate") = false,
         "AGEX interest points of a frame (the depth pipeline, agex_keypoints's): dicts of position, orientation, "
         "pixel, rank, mesh, geodesic_distance. Settings: the model's pipeline (model=path) or the defaults, "
         "overridden by keyword by their model-file keys (k=5, delta_connected=0.03, crop_min=[...], ...).");
  m.def ("bundled_data_file", &bundledDataFile, py::arg ("relative"),
         "The path of a file shipped with agex, relative to data/ (e.g. 'models/agex_bonn.yml')");
}

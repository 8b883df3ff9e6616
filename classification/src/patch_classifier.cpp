#include <agex/classification/patch_classifier.h>

#include <agex/io/atomic_file.h>
#include <agex/io/input_file.h>

#include "checked_read.h"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
/** Metadata JSON is stored as a list of chunks of at most this many characters:
  * cv::FileStorage refuses strings longer than 4096 characters. */
constexpr std::size_t kMetadataChunk = 1000;
/** Each chunk is written as '|' + text + '|' so that FileStorage quotes it and keeps it
  * verbatim: it trims unquoted strings and takes "..." or '...' for already quoted. */
constexpr char kChunkFence = '|';
/** classify () keeps features on the stack up to this many fragments. */
constexpr std::size_t kStackFeatures = 2048;
/** Bounds of a cascade, the same for training parameters and model files. */
constexpr std::size_t kMaxCascadeStages = 32;
constexpr std::size_t kMaxCascadeLevels = 16;
/** Most auxiliary features a classifier may have (a bound for damaged files too). */
constexpr std::size_t kMaxAuxiliaryFeatures = 1024;

using detail::readInt;
using detail::readReal;



/** Checks the parts of a booster node that cv::ml reads without checking (it indexes
  * arrays with them), so that a damaged file fails here instead of in OpenCV. */
void
checkBoosterNode (const cv::FileNode &node, int features)
{
  if (!node.isMap ())
    throw ModelError ("not a map");
  if (readInt (node, "format") != 3)
    throw ModelError ("unsupported cv::ml tree format (need 3)");
  // cv::ml writes var_idx (all features, in order) even when every variable is used;
  // anything else would remap the split variables.
  const cv::FileNode var_idx = node["var_idx"];
  if (!var_idx.empty ())
  {
    if (!var_idx.isSeq () || static_cast<int> (var_idx.size ()) != features)
      throw ModelError ("var_idx does not list the " + std::to_string (features) + " dictionary fragments");
    int k = 0;
    for (cv::FileNodeIterator it = var_idx.begin (); it != var_idx.end (); ++it, ++k)
      if (!(*it).isInt () || static_cast<int> (*it) != k)
        throw ModelError ("var_idx does not list the dictionary fragments in order");
  }
  const cv::FileNode types = node["var_type"];
  if (types.empty () || !types.isSeq () || static_cast<int> (types.size ()) != features + 1)
    throw ModelError ("var_type does not match the " + std::to_string (features) + " dictionary fragments");
  int i = 0;
  for (cv::FileNodeIterator it = types.begin (); it != types.end (); ++it, ++i)
    if (!(*it).isInt () || (i < features && static_cast<int> (*it) != 0))
      throw ModelError ("a feature is not an ordered variable");
  if (readInt (node, "var_all") != features + 1 || readInt (node, "var_count") != features)
    throw ModelError ("var_all/var_count do not match the " + std::to_string (features) + " dictionary fragments");
  const cv::FileNode trees = node["trees"];
  if (trees.empty () || !trees.isSeq () || trees.size () == 0)
    throw ModelError ("no trees");
  if (readInt (node, "ntrees") != static_cast<int> (trees.size ()))
    throw ModelError ("ntrees does not match the trees");
  for (cv::FileNodeIterator t = trees.begin (); t != trees.end (); ++t)
  {
    const cv::FileNode nodes = (*t)["nodes"];
    if (nodes.empty () || !nodes.isSeq () || nodes.size () == 0)
      throw ModelError ("a tree without nodes");
    for (cv::FileNodeIterator n = nodes.begin (); n != nodes.end (); ++n)
    {
      if (!(*n).isMap ())
        throw ModelError ("a tree node is not a map");
      const cv::FileNode splits = (*n)["splits"];
      if (splits.empty ())
        continue;
      if (!splits.isSeq ())
        throw ModelError ("invalid splits");
      for (cv::FileNodeIterator s = splits.begin (); s != splits.end (); ++s)
      {
        const int var = readInt (*s, "var");
        if (var < 0 || var >= features)
          throw ModelError ("a split uses feature " + std::to_string (var) + " of " + std::to_string (features));
        const cv::FileNode le = (*s)["le"], gt = (*s)["gt"];
        const cv::FileNode c = le.empty () ? gt : le;
        if (c.empty () || !(c.isReal () || c.isInt ()))
          throw ModelError ("a split without a threshold");
      }
    }
  }
}

std::string
readWholeFile (const std::string &path)
{
  std::error_code ec;
  if (!std::filesystem::exists (path, ec))
    throw ModelError (path + ": model file not found");
  if (std::filesystem::is_directory (path, ec))
    throw ModelError (path + ": is a directory, not a model file");
  // Before opening: a FIFO would block until some other process writes to it.
  const std::string problem = notARegularFile (path);
  if (!problem.empty ())
    throw ModelError (path + ": " + problem + "; models are read from regular files only");
  const auto size = std::filesystem::file_size (path, ec);
  if (!ec && size > kMaxModelFileBytes)
    throw ModelError (path + ": " + std::to_string (size) + " bytes, more than the " +
                      std::to_string (kMaxModelFileBytes) + " of any agex model");
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw ModelError (path + ": cannot open the model file: " + std::strerror (errno));
  std::ostringstream bytes;
  bytes << in.rdbuf ();
  if (in.bad ())
    throw ModelError (path + ": cannot read the model file");
  return bytes.str ();
}

/** What train () learns about its input before fitting: the positives of each class, the
  * patch size and pitch, and the largest |cell| (the clamp). */
struct TrainingSet
{
  std::vector<std::vector<const agex::DepthPatch *>> positives;
  int size = 0;
  float pitch = 0.f;
  float clamp = 0.f;
};

/** \throws std::invalid_argument on any input train () cannot use (see its comment). */
TrainingSet
checkTrainingSet (const std::vector<agex::DepthPatch> &patches, const std::vector<int> &labels, int classes,
                  const PatchClassifierParams &params)
{
  if (patches.empty ())
    throw std::invalid_argument ("PatchClassifier::train: no patches");
  if (patches.size () != labels.size ())
    throw std::invalid_argument ("PatchClassifier::train: " + std::to_string (patches.size ()) + " patches but " +
                                 std::to_string (labels.size ()) + " labels");
  if (classes < 1)
    throw std::invalid_argument ("PatchClassifier::train: classes must be at least 1");
  if (params.weak_count < 1)
    throw std::invalid_argument ("PatchClassifier::train: weak_count must be at least 1");
  if (!(params.weight_trim_rate >= 0.0 && params.weight_trim_rate <= 1.0))
    throw std::invalid_argument ("PatchClassifier::train: weight_trim_rate must be in [0, 1]");
  if (params.cascade_stage_ends.size () > kMaxCascadeStages || params.cascade_levels.size () > kMaxCascadeLevels)
    throw std::invalid_argument ("PatchClassifier::train: at most " + std::to_string (kMaxCascadeStages) +
                                 " cascade stages and " + std::to_string (kMaxCascadeLevels) + " cascade levels");
  for (std::size_t s = 0; s < params.cascade_stage_ends.size (); ++s)
    if (params.cascade_stage_ends[s] < 1 || (s > 0 && params.cascade_stage_ends[s] <= params.cascade_stage_ends[s - 1]))
      throw std::invalid_argument ("PatchClassifier::train: cascade_stage_ends must increase from 1");
  for (std::size_t l = 0; l < params.cascade_levels.size (); ++l)
    if (!(params.cascade_levels[l] > 0.f && params.cascade_levels[l] < 1.f) ||
        (l > 0 && params.cascade_levels[l] <= params.cascade_levels[l - 1]))
      throw std::invalid_argument ("PatchClassifier::train: cascade_levels must increase within (0, 1)");
  if (params.cascade_miss_rates.size () > kMaxCascadeLevels)
    throw std::invalid_argument ("PatchClassifier::train: at most " + std::to_string (kMaxCascadeLevels) +
                                 " cascade miss rates");
  for (std::size_t m = 0; m < params.cascade_miss_rates.size (); ++m)
    if (!(params.cascade_miss_rates[m] >= 0.f && params.cascade_miss_rates[m] <= 0.5f) ||
        (m > 0 && params.cascade_miss_rates[m] <= params.cascade_miss_rates[m - 1]))
      throw std::invalid_argument ("PatchClassifier::train: cascade_miss_rates must increase within [0, 0.5]");

  TrainingSet set;
  const int n = set.size = patches.front ().size;
  const float pitch = set.pitch = patches.front ().metres_per_cell;
  if (n < 1 || n > agex::DepthPatch::kMaxSize)
    throw std::invalid_argument ("PatchClassifier::train: patch size " + std::to_string (n) + " outside 1.." +
                                 std::to_string (agex::DepthPatch::kMaxSize));
  set.positives.resize (static_cast<std::size_t> (classes));
  std::vector<int> negatives (static_cast<std::size_t> (classes), 0);
  for (std::size_t i = 0; i < patches.size (); ++i)
  {
    const agex::DepthPatch &p = patches[i];
    if (p.size != n)
      throw std::invalid_argument ("PatchClassifier::train: patch " + std::to_string (i) + " has size " +
                                   std::to_string (p.size) + ", patch 0 has " + std::to_string (n));
    if (!(std::fabs (p.metres_per_cell - pitch) <= 1e-4f * std::fabs (pitch)))
      throw std::invalid_argument ("PatchClassifier::train: patch " + std::to_string (i) +
                                   " has another cell pitch (metres_per_cell) than patch 0");
    for (int k = 0; k < n * n; ++k)
    {
      if (!std::isfinite (p.patch[k]))
        throw std::invalid_argument ("PatchClassifier::train: patch " + std::to_string (i) + " has a non-finite cell");
      set.clamp = std::max (set.clamp, std::fabs (p.patch[k]));
    }
    const int label = labels[i];
    if (label < -1 || label >= classes)
      throw std::invalid_argument ("PatchClassifier::train: label " + std::to_string (label) + " of patch " +
                                   std::to_string (i) + " outside -1.." + std::to_string (classes - 1));
    for (int c = 0; c < classes; ++c)
      if (c == label)
        set.positives[c].push_back (&p);
      else
        ++negatives[c];
  }
  for (int c = 0; c < classes; ++c)
  {
    if (set.positives[c].empty ())
      throw std::invalid_argument ("PatchClassifier::train: class " + std::to_string (c) + " has no positives");
    if (negatives[c] == 0)
      throw std::invalid_argument ("PatchClassifier::train: class " + std::to_string (c) +
                                   " has no negatives (every patch is of that class)");
  }
  return set;
}

/** Every feature of the patches listed in rows (all patches when rows is null), once:
  * N x (F + A) floats (the fragments, then the auxiliary features), rows in parallel (each
  * row is independent, so the result does not depend on the threads). */
cv::Mat
featureRows (const FragmentDictionary &dictionary, const std::vector<agex::DepthPatch> &patches,
             const std::vector<std::vector<float>> &auxiliary, std::size_t auxiliary_count,
             const std::vector<std::size_t> *rows = nullptr)
{
  const int fragments = static_cast<int> (dictionary.size ());
  const std::size_t count = rows ? rows->size () : patches.size ();
  cv::Mat samples (static_cast<int> (count), fragments + static_cast<int> (auxiliary_count), CV_32F);
  cv::parallel_for_ (cv::Range (0, samples.rows), [&] (const cv::Range &range) {
    for (int r = range.start; r < range.end; ++r)
    {
      const std::size_t i = rows ? (*rows)[static_cast<std::size_t> (r)] : static_cast<std::size_t> (r);
      float *row = samples.ptr<float> (r);
      dictionary.computeFeatures (patches[i], row);
      for (std::size_t a = 0; a < auxiliary_count; ++a)
        row[fragments + static_cast<int> (a)] = auxiliary[i][a];
    }
  });
  return samples;
}

/** \throws std::invalid_argument unless auxiliary holds `names` finite values per patch (or
  * nothing when there are no names). */
void
checkAuxiliary (const std::vector<std::vector<float>> &auxiliary, std::size_t names, std::size_t patches,
                const char *caller)
{
  const std::string where = std::string ("PatchClassifier::") + caller + ": ";
  if (names > kMaxAuxiliaryFeatures)
    throw std::invalid_argument (where + "more than " + std::to_string (kMaxAuxiliaryFeatures) + " auxiliary features");
  if (names > 0 && auxiliary.size () != patches)
    throw std::invalid_argument (where + std::to_string (auxiliary.size ()) + " rows of auxiliary features for " +
                                 std::to_string (patches) + " patches");
  for (std::size_t i = 0; i < auxiliary.size () && names > 0; ++i)
  {
    if (auxiliary[i].size () != names)
      throw std::invalid_argument (where + "auxiliary row " + std::to_string (i) + " has " +
                                   std::to_string (auxiliary[i].size ()) + " values, not " + std::to_string (names));
    for (const float v : auxiliary[i])
      if (!std::isfinite (v))
        throw std::invalid_argument (where + "auxiliary row " + std::to_string (i) + " has a non-finite value");
  }
}

/** The GentleBoost stumps of class c against everything else. */
cv::Ptr<cv::ml::Boost>
trainBooster (const cv::Mat &samples, const std::vector<int> &labels, int c, const PatchClassifierParams &params)
{
  // Binary responses: cv::ml::Boost maps the larger label to +1, so the margin is
  // positive for class c.
  cv::Mat responses (samples.rows, 1, CV_32S);
  for (int i = 0; i < samples.rows; ++i)
    responses.at<int> (i) = labels[static_cast<std::size_t> (i)] == c ? 1 : 0;
  cv::Ptr<cv::ml::TrainData> data = cv::ml::TrainData::create (samples, cv::ml::ROW_SAMPLE, responses);
  cv::Ptr<cv::ml::Boost> boost = cv::ml::Boost::create ();
  boost->setBoostType (cv::ml::Boost::GENTLE);
  boost->setWeakCount (params.weak_count);
  boost->setWeightTrimRate (params.weight_trim_rate);
  boost->setMaxDepth (1);
  boost->setUseSurrogates (false);
  boost->setCVFolds (0);
  boost->setMinSampleCount (2);
  boost->setRegressionAccuracy (0.f);
  bool ok = false;
  try
  {
    ok = boost->train (data);
  }
  catch (const cv::Exception &e)
  {
    throw std::runtime_error ("PatchClassifier::train: cv::ml::Boost failed for class " + std::to_string (c) + ": " +
                              e.err);
  }
  if (!ok || !boost->isTrained ())
    throw std::runtime_error ("PatchClassifier::train: cv::ml::Boost failed for class " + std::to_string (c));
  return boost;
}

/** train_class (c) for every class on up to workers threads (cv::ml trains a tree on one
  * thread, so the classes go side by side; each booster is deterministic, whatever its
  * thread). progress is called on this thread as classes finish; the first failure (of a
  * class or of progress) stops the rest and is rethrown. */
std::vector<cv::Ptr<cv::ml::Boost>>
trainBoosters (int classes, int workers, const std::function<cv::Ptr<cv::ml::Boost> (int)> &train_class,
               const std::function<void (int, int)> &progress)
{
  std::vector<cv::Ptr<cv::ml::Boost>> boosters (static_cast<std::size_t> (classes));
  if (workers == 1)
  {
    for (int c = 0; c < classes; ++c)
    {
      boosters[static_cast<std::size_t> (c)] = train_class (c);
      if (progress)
        progress (c + 1, classes);
    }
    return boosters;
  }
  std::mutex mutex;
  std::condition_variable changed;
  int next = 0, finished = 0;
  bool stop = false;
  std::exception_ptr error;
  const auto work = [&] () {
    for (;;)
    {
      int c;
      {
        std::lock_guard<std::mutex> lock (mutex);
        if (stop || next >= classes)
          return;
        c = next++;
      }
      cv::Ptr<cv::ml::Boost> boost;
      std::exception_ptr failure;
      try
      {
        boost = train_class (c);
      }
      catch (...)
      {
        failure = std::current_exception ();
      }
      std::lock_guard<std::mutex> lock (mutex);
      if (failure)
      {
        if (!error)
          error = failure;
        stop = true;
      }
      else
        boosters[static_cast<std::size_t> (c)] = boost;
      ++finished;
      changed.notify_all ();
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < workers; ++t)
    threads.emplace_back (work);
  std::exception_ptr progress_error;
  int reported = 0;
  while (reported < classes && !progress_error)
  {
    int now;
    {
      std::unique_lock<std::mutex> lock (mutex);
      changed.wait (lock, [&] { return finished > reported || stop; });
      if (stop)
        break;
      now = finished;
    }
    while (reported < now && !progress_error)
    {
      ++reported;
      if (!progress)
        continue;
      try
      {
        progress (reported, classes);
      }
      catch (...)
      {
        progress_error = std::current_exception ();
        std::lock_guard<std::mutex> lock (mutex);
        stop = true;
      }
    }
  }
  for (std::thread &t : threads)
    t.join ();
  if (error)
    std::rethrow_exception (error);
  if (progress_error)
    std::rethrow_exception (progress_error);
  return boosters;
}
}  // namespace

std::size_t
yamlNestingBound (const std::string &yaml, std::size_t limit, std::size_t *line)
{
  constexpr std::size_t kNone = static_cast<std::size_t> (-1);
  std::size_t bound = 0, bound_line = 1, flow = 0;
  // The smallest indentation a line continuing any counted flow collection may have: an
  // opener first on its line may belong to a collection whose continuation lines need only
  // column 1; one after other text on a line indented c belongs to a block item (or the
  // root) on that line, so continuation lines need at least column c + 1.
  std::size_t continuation = kNone;
  std::size_t number = 0;
  for (std::size_t begin = 0; begin < yaml.size ();)
  {
    ++number;
    std::size_t end = yaml.find ('\n', begin);
    if (end == std::string::npos)
      end = yaml.size ();
    std::size_t c = begin;
    while (c < end && yaml[c] == ' ')
      ++c;
    const auto first = c < end ? static_cast<unsigned char> (yaml[c]) : 0u;
    // OpenCV skips a comment line and the rest of a line at a control character (or refuses
    // it); only a line with something printable first can hold structure.
    if (first > ' ' && first != '#')
    {
      const std::size_t column = c - begin;
      if (flow > 0 && column < continuation)
      {
        flow = 0;  // every open flow collection would end here (or OpenCV refuses the line)
        continuation = kNone;
      }
      std::size_t markers = 0;
      for (std::size_t i = c; i < end; ++i)
      {
        const char ch = yaml[i];
        if (ch == '[' || ch == '{')
        {
          ++flow;
          continuation = std::min (continuation, i == c ? std::size_t (1) : column + 1);
        }
        else if (ch == ':' || ch == '-')
          ++markers;
        const std::size_t depth = flow + column + 1 + markers;
        if (depth > bound)
        {
          bound = depth;
          bound_line = number;
          if (bound > limit)
          {
            if (line)
              *line = bound_line;
            return bound;
          }
        }
      }
    }
    begin = end + 1;
  }
  if (line)
    *line = bound_line;
  return bound;
}

void
PatchClassifier::train (const std::vector<agex::DepthPatch> &patches, const std::vector<int> &labels, int classes,
                        const PatchClassifierParams &params, const std::function<void (int, int)> &progress)
{
  train (patches, {}, {}, labels, classes, params, progress);
}

void
PatchClassifier::train (const std::vector<agex::DepthPatch> &patches, const std::vector<std::vector<float>> &auxiliary,
                        const std::vector<std::string> &auxiliary_names, const std::vector<int> &labels, int classes,
                        const PatchClassifierParams &params, const std::function<void (int, int)> &progress)
{
  const TrainingSet set = checkTrainingSet (patches, labels, classes, params);
  checkAuxiliary (auxiliary, auxiliary_names.size (), patches.size (), "train");
  FragmentDictionary dictionary;
  dictionary.build (set.positives, params.dictionary);
  const cv::Mat samples = featureRows (dictionary, patches, auxiliary, auxiliary_names.size ());
  const int workers = std::max (1, std::min (classes, cv::getNumThreads ()));
  auto boosters = trainBoosters (
      classes, workers, [&] (int c) { return trainBooster (samples, labels, c, params); }, progress);

  PatchClassifier trained;
  trained.dictionary_ = std::move (dictionary);
  trained.auxiliary_names_ = auxiliary_names;
  trained.boosters_ = std::move (boosters);
  trained.geometry_.size = set.size;
  trained.geometry_.extent = static_cast<float> (set.size) * set.pitch;
  trained.geometry_.clamp = set.clamp;
  trained.params_ = params;
  try
  {
    trained.prepare ();
    trained.fitCascadeToRows (samples, labels);
    trained.prepareCascade ();
  }
  catch (const ModelError &e)
  {
    throw std::runtime_error (std::string ("PatchClassifier::train: unusable boosters: ") + e.what ());
  }
  *this = std::move (trained);
}

void
PatchClassifier::prepare ()
{
  const int fragments = static_cast<int> (dictionary_.size ());
  const int features = fragments + static_cast<int> (auxiliary_names_.size ());
  std::vector<ClassTrees> all;
  std::vector<char> used (static_cast<std::size_t> (features), 0);
  for (std::size_t c = 0; c < boosters_.size (); ++c)
  {
    const std::string where = "booster " + std::to_string (c) + ": ";
    const cv::Ptr<cv::ml::Boost> &b = boosters_[c];
    if (!b || !b->isTrained ())
      throw ModelError (where + "not trained");
    if (b->getVarCount () != features)
      throw ModelError (where + "uses " + std::to_string (b->getVarCount ()) + " features, the dictionary and the " +
                        "auxiliary features have " + std::to_string (features));
    const std::vector<int> &roots = b->getRoots ();
    const std::vector<cv::ml::DTrees::Node> &nodes = b->getNodes ();
    const std::vector<cv::ml::DTrees::Split> &splits = b->getSplits ();
    if (roots.empty ())
      throw ModelError (where + "no trees");
    ClassTrees trees;
    trees.roots = roots;
    trees.nodes.resize (nodes.size ());
    const int node_count = static_cast<int> (nodes.size ());
    for (int i = 0; i < node_count; ++i)
    {
      const cv::ml::DTrees::Node &src = nodes[static_cast<std::size_t> (i)];
      TreeNode &dst = trees.nodes[static_cast<std::size_t> (i)];
      dst.value = src.value;
      if (src.split < 0)
        continue;
      if (src.split >= static_cast<int> (splits.size ()))
        throw ModelError (where + "a node refers to a missing split");
      const cv::ml::DTrees::Split &split = splits[static_cast<std::size_t> (src.split)];
      if (split.varIdx < 0 || split.varIdx >= features)
        throw ModelError (where + "a split uses feature " + std::to_string (split.varIdx) + " of " +
                          std::to_string (features));
      if (src.left < 0 || src.left >= node_count || src.right < 0 || src.right >= node_count)
        throw ModelError (where + "a split node without both children");
      dst.feature = split.varIdx;
      dst.threshold = split.c;
      dst.left = src.left;
      dst.right = src.right;
    }
    // Every root must reach leaves in fewer steps than there are nodes (no cycles).
    for (int root : roots)
    {
      if (root < 0 || root >= node_count)
        throw ModelError (where + "a tree without a root");
      std::vector<int> stack{root};
      int visits = 0;
      while (!stack.empty ())
      {
        const int i = stack.back ();
        stack.pop_back ();
        if (++visits > node_count)
          throw ModelError (where + "a tree is not a tree");
        const TreeNode &node = trees.nodes[static_cast<std::size_t> (i)];
        if (node.feature >= 0)
        {
          used[static_cast<std::size_t> (node.feature)] = 1;
          stack.push_back (node.left);
          stack.push_back (node.right);
        }
      }
    }
    // Every tree a stump (a split whose children are leaves)? Then a flat copy.
    bool stumps = true;
    for (int root : roots)
    {
      const TreeNode &node = trees.nodes[static_cast<std::size_t> (root)];
      stumps = stumps && node.feature >= 0 && trees.nodes[static_cast<std::size_t> (node.left)].feature < 0 &&
               trees.nodes[static_cast<std::size_t> (node.right)].feature < 0;
    }
    if (stumps)
      for (int root : roots)
      {
        const TreeNode &node = trees.nodes[static_cast<std::size_t> (root)];
        trees.stumps.push_back ({node.feature, node.threshold, trees.nodes[static_cast<std::size_t> (node.left)].value,
                                 trees.nodes[static_cast<std::size_t> (node.right)].value});
      }
    all.push_back (std::move (trees));
  }
  std::vector<int> list;
  for (int f = 0; f < fragments; ++f)  // the auxiliary features are given, not computed
    if (used[static_cast<std::size_t> (f)])
      list.push_back (f);
  trees_ = std::move (all);
  used_fragments_ = std::move (list);
}

void
PatchClassifier::classify (const agex::DepthPatch &patch, float *margins, float *confidences) const
{
  classify (patch, nullptr, margins, confidences);
}

void
PatchClassifier::checkClassifyInput (const agex::DepthPatch &patch, const float *auxiliary, const char *caller) const
{
  if (!auxiliary && !auxiliary_names_.empty ())
    throw std::invalid_argument (std::string ("PatchClassifier::") + caller + ": the classifier needs " +
                                 std::to_string (auxiliary_names_.size ()) + " auxiliary features");
  if (!trained ())
    throw std::logic_error (std::string ("PatchClassifier::") + caller + ": the classifier is not trained");
  if (patch.size != geometry_.size)
    throw std::invalid_argument (std::string ("PatchClassifier::") + caller + ": patch size " +
                                 std::to_string (patch.size) + ", the model was trained on " +
                                 std::to_string (geometry_.size));
}

namespace
{
/** Feature storage for one classify call: on the stack up to kStackFeatures. */
class FeatureBuffer
{
public:
  explicit FeatureBuffer (std::size_t count)
  {
    if (count > kStackFeatures)
    {
      heap_.resize (count);
      data_ = heap_.data ();
    }
  }
  float *data () { return data_; }

private:
  float stack_[kStackFeatures];
  std::vector<float> heap_;
  float *data_ = stack_;
};

void
writeOutputs (const double *sums, std::size_t classes, float *margins, float *confidences)
{
  for (std::size_t c = 0; c < classes; ++c)
  {
    const float margin = static_cast<float> (sums[c]);
    if (margins)
      margins[c] = margin;
    if (confidences)
      confidences[c] = static_cast<float> (1.0 / (1.0 + std::exp (-2.0 * static_cast<double> (margin))));
  }
}

/** A classifier has few classes; more than this keep their sums on the heap. */
constexpr std::size_t kStackClasses = 16;
}  // namespace

void
PatchClassifier::classify (const agex::DepthPatch &patch, const float *auxiliary, float *margins,
                           float *confidences) const
{
  checkClassifyInput (patch, auxiliary, "classify");
  FeatureBuffer buffer (dictionary_.size () + auxiliary_names_.size ());
  float *features = buffer.data ();
  dictionary_.computeFeatures (patch, used_fragments_, features);
  std::copy (auxiliary, auxiliary + auxiliary_names_.size (), features + dictionary_.size ());
  for (std::size_t c = 0; c < trees_.size (); ++c)
  {
    // cv::ml::DTreesImpl::predictTrees with PREDICT_SUM: trees in order, a double sum,
    // "value <= threshold" goes left; the features are never cv::ml's missing value.
    const ClassTrees &t = trees_[c];
    double sum = 0.0;
    if (!t.stumps.empty ())
      for (const Stump &s : t.stumps)
        sum += features[s.feature] <= s.threshold ? s.left : s.right;
    else
      for (int root : t.roots)
      {
        const TreeNode *node = &t.nodes[static_cast<std::size_t> (root)];
        while (node->feature >= 0)
          node = &t.nodes[static_cast<std::size_t> (features[node->feature] <= node->threshold ? node->left
                                                                                               : node->right)];
        sum += node->value;
      }
    writeOutputs (&sum, 1, margins ? margins + c : nullptr, confidences ? confidences + c : nullptr);
  }
}

bool
PatchClassifier::classifyCascade (const agex::DepthPatch &patch, const float *auxiliary, float min_confidence,
                                  float *margins, float *confidences, float max_miss_rate) const
{
  if (!(max_miss_rate >= 0.f))
    throw std::invalid_argument ("PatchClassifier::classifyCascade: max_miss_rate must be a number >= 0");
  const int level = stage_fragments_.empty () ? -1 : cascade_.levelFor (min_confidence);
  const int rate = stage_fragments_.empty () ? -1 : cascade_.rateFor (max_miss_rate);
  if (level < 0 || rate < 0)
  {
    classify (patch, auxiliary, margins, confidences);
    return true;
  }
  checkClassifyInput (patch, auxiliary, "classifyCascade");
  FeatureBuffer buffer (dictionary_.size () + auxiliary_names_.size ());
  float *features = buffer.data ();
  std::copy (auxiliary, auxiliary + auxiliary_names_.size (), features + dictionary_.size ());
  FragmentDictionary::PreparedPatch prepared;
  dictionary_.prepare (patch, prepared);

  const std::size_t classes = trees_.size ();
  double stack_sums[kStackClasses] = {};
  std::vector<double> heap_sums (classes > kStackClasses ? classes : 0, 0.0);
  double *sums = classes > kStackClasses ? heap_sums.data () : stack_sums;
  const std::size_t stages = cascade_.stage_ends.size ();
  std::size_t round = 0;
  for (std::size_t s = 0; s <= stages; ++s)
  {
    const std::vector<int> &fragments = stage_fragments_[s];
    dictionary_.computeFeatures (prepared, fragments.data (), fragments.size (), features);
    const std::size_t end =
        s < stages ? static_cast<std::size_t> (cascade_.stage_ends[s]) : std::numeric_limits<std::size_t>::max ();
    bool alive = s == stages;
    for (std::size_t c = 0; c < classes; ++c)
    {
      // The same stumps in the same order as classify (): the same double sums.
      const std::vector<Stump> &stumps = trees_[c].stumps;
      const std::size_t stop = std::min (end, stumps.size ());
      double sum = sums[c];
      for (std::size_t r = round; r < stop; ++r)
      {
        const Stump &st = stumps[r];
        sum += features[st.feature] <= st.threshold ? st.left : st.right;
      }
      sums[c] = sum;
      alive = alive || sum >= static_cast<double> (cascade_.threshold (static_cast<std::size_t> (rate),
                                                                       static_cast<std::size_t> (level), c, s));
    }
    round = end;
    if (!alive)
    {
      writeOutputs (sums, classes, margins, confidences);
      return false;
    }
  }
  writeOutputs (sums, classes, margins, confidences);
  return true;
}

int
SoftCascade::rateFor (float max_miss_rate) const
{
  int found = -1;
  for (std::size_t m = 0; m < miss_rates.size () && !stage_ends.empty () && !levels.empty (); ++m)
    if (miss_rates[m] <= max_miss_rate)
      found = static_cast<int> (m);
  return found;
}

int
SoftCascade::levelFor (float min_confidence) const
{
  int found = -1;
  for (std::size_t l = 0; l < levels.size () && !stage_ends.empty (); ++l)
    if (levels[l] <= min_confidence)
      found = static_cast<int> (l);
  return found;
}

namespace
{
/** A threshold no partial margin falls below: a class none of whose positives reached the level. */
constexpr float kNeverBelow = -1e30f;

/** \throws ModelError describing what in the cascade is out of range. */
void
checkCascade (const SoftCascade &cascade, std::size_t classes, std::size_t rounds)
{
  if (cascade.stage_ends.empty () || cascade.stage_ends.size () > kMaxCascadeStages)
    throw ModelError ("the cascade needs 1 to " + std::to_string (kMaxCascadeStages) + " stages");
  if (cascade.levels.empty () || cascade.levels.size () > kMaxCascadeLevels)
    throw ModelError ("the cascade needs 1 to " + std::to_string (kMaxCascadeLevels) + " levels");
  for (std::size_t s = 0; s < cascade.stage_ends.size (); ++s)
    if (cascade.stage_ends[s] < 1 || static_cast<std::size_t> (cascade.stage_ends[s]) >= rounds ||
        (s > 0 && cascade.stage_ends[s] <= cascade.stage_ends[s - 1]))
      throw ModelError ("the cascade's stage ends must increase from 1 to below the " + std::to_string (rounds) +
                        " rounds");
  for (std::size_t l = 0; l < cascade.levels.size (); ++l)
    if (!(cascade.levels[l] > 0.f && cascade.levels[l] < 1.f) || (l > 0 && cascade.levels[l] <= cascade.levels[l - 1]))
      throw ModelError ("the cascade's levels must increase within (0, 1)");
  if (cascade.miss_rates.empty () || cascade.miss_rates.size () > kMaxCascadeLevels)
    throw ModelError ("the cascade needs 1 to " + std::to_string (kMaxCascadeLevels) + " miss rates");
  for (std::size_t m = 0; m < cascade.miss_rates.size (); ++m)
    if (!(cascade.miss_rates[m] >= 0.f && cascade.miss_rates[m] <= 0.5f) ||
        (m > 0 && cascade.miss_rates[m] <= cascade.miss_rates[m - 1]))
      throw ModelError ("the cascade's miss rates must increase within [0, 0.5]");
  if (cascade.classes != static_cast<int> (classes) ||
      cascade.thresholds.size () !=
          cascade.miss_rates.size () * cascade.levels.size () * classes * cascade.stage_ends.size ())
    throw ModelError ("the cascade needs miss rates x levels x classes x stages thresholds");
  for (const float t : cascade.thresholds)
    if (!(std::fabs (t) <= -kNeverBelow))
      throw ModelError ("a cascade threshold is not a number within +-1e30");
}

/** The float at most v (a threshold rounded up could reject the positive that set it). */
float
floatAtMost (double v)
{
  float f = static_cast<float> (v);
  if (static_cast<double> (f) > v)
    f = std::nextafter (f, -std::numeric_limits<float>::infinity ());
  return f;
}
}  // namespace

void
PatchClassifier::fitCascadeToRows (const cv::Mat &samples, const std::vector<int> &labels)
{
  cascade_ = SoftCascade ();
  stage_fragments_.clear ();
  std::size_t rounds = 0;
  for (const ClassTrees &t : trees_)
  {
    if (t.stumps.empty ())
      return;  // trees deeper than stumps: no cascade
    rounds = std::max (rounds, t.stumps.size ());
  }
  SoftCascade cascade;
  for (const int e : params_.cascade_stage_ends)
    if (e >= 1 && static_cast<std::size_t> (e) < rounds && (cascade.stage_ends.empty () || e > cascade.stage_ends.back ()))
      cascade.stage_ends.push_back (e);
  cascade.levels = params_.cascade_levels;
  cascade.miss_rates = params_.cascade_miss_rates;
  cascade.classes = static_cast<int> (trees_.size ());
  if (cascade.empty ())
    return;
  const std::size_t stages = cascade.stage_ends.size (), levels = cascade.levels.size ();
  const std::size_t classes = trees_.size ();
  cascade.thresholds.assign (cascade.miss_rates.size () * levels * classes * stages, kNeverBelow);
  for (std::size_t c = 0; c < classes; ++c)
  {
    // Each positive's partial margins at the stage ends, and its confidence as classify ()
    // reports it.
    const std::vector<Stump> &stumps = trees_[c].stumps;
    std::vector<double> partials;  // positive-major: stages values each
    std::vector<float> confidences;
    for (int i = 0; i < samples.rows; ++i)
    {
      if (labels[static_cast<std::size_t> (i)] != static_cast<int> (c))
        continue;
      const float *row = samples.ptr<float> (i);
      double sum = 0.0;
      std::size_t s = 0;
      for (std::size_t r = 0; r < stumps.size (); ++r)
      {
        if (s < stages && r == static_cast<std::size_t> (cascade.stage_ends[s]))
        {
          partials.push_back (sum);
          ++s;
        }
        sum += row[stumps[r].feature] <= stumps[r].threshold ? stumps[r].left : stumps[r].right;
      }
      for (; s < stages; ++s)  // a class with fewer rounds than a stage end: its final sum
        partials.push_back (sum);
      float confidence = 0.f;
      writeOutputs (&sum, 1, nullptr, &confidence);
      confidences.push_back (confidence);
    }
    for (std::size_t l = 0; l < levels; ++l)
    {
      std::vector<std::size_t> reaching;  // the positives kept at this level
      for (std::size_t i = 0; i < confidences.size (); ++i)
        if (confidences[i] >= cascade.levels[l])
          reaching.push_back (i);
      for (std::size_t m = 0; m < cascade.miss_rates.size (); ++m)
      {
        // Each stage rejects the lowest (rate / stages) of the positives the level keeps
        // (ties stay), at rate 0 none: its threshold is the lowest survivor's partial margin.
        const std::size_t per_stage = static_cast<std::size_t> (
            std::floor (static_cast<double> (cascade.miss_rates[m]) * static_cast<double> (reaching.size ()) /
                        static_cast<double> (stages)));
        std::vector<std::size_t> alive = reaching;
        std::vector<double> values;
        for (std::size_t k = 0; k < stages && !alive.empty (); ++k)
        {
          values.clear ();
          for (const std::size_t i : alive)
            values.push_back (partials[i * stages + k]);
          const std::size_t cut = std::min (per_stage, values.size () - 1);
          std::nth_element (values.begin (), values.begin () + static_cast<std::ptrdiff_t> (cut), values.end ());
          const float threshold = std::max (kNeverBelow, floatAtMost (values[cut]));
          // (A partial margin below -1e30 would need 1e30 / 150 per stump: none is that large.)
          cascade.thresholds[((m * levels + l) * classes + c) * stages + k] = threshold;
          std::vector<std::size_t> kept;
          for (const std::size_t i : alive)
            if (partials[i * stages + k] >= static_cast<double> (threshold))
              kept.push_back (i);
          alive.swap (kept);
        }
      }
    }
  }
  cascade_ = std::move (cascade);
}

void
PatchClassifier::fitCascade (const std::vector<agex::DepthPatch> &patches,
                             const std::vector<std::vector<float>> &auxiliary, const std::vector<int> &labels,
                             const std::vector<int> &stage_ends, const std::vector<float> &levels,
                             const std::vector<float> &miss_rates)
{
  if (!trained ())
    throw std::logic_error ("PatchClassifier::fitCascade: the classifier is not trained");
  PatchClassifierParams params = params_;
  params.cascade_stage_ends = stage_ends;
  params.cascade_levels = levels;
  params.cascade_miss_rates = miss_rates;
  checkTrainingSet (patches, labels, classes (), params);
  if (patches.front ().size != geometry_.size)
    throw std::invalid_argument ("PatchClassifier::fitCascade: patch size " + std::to_string (patches.front ().size) +
                                 ", the model was trained on " + std::to_string (geometry_.size));
  checkAuxiliary (auxiliary, auxiliary_names_.size (), patches.size (), "fitCascade");
  // The positives' features only: negatives set no threshold.
  std::vector<std::size_t> rows;
  std::vector<int> positive_labels;
  for (std::size_t i = 0; i < patches.size (); ++i)
    if (labels[i] >= 0)
    {
      rows.push_back (i);
      positive_labels.push_back (labels[i]);
    }
  const cv::Mat samples = featureRows (dictionary_, patches, auxiliary, auxiliary_names_.size (), &rows);
  // Fitted on a copy: a refused fit leaves this classifier as it was.
  PatchClassifier fitted = *this;
  fitted.params_ = params;
  try
  {
    fitted.fitCascadeToRows (samples, positive_labels);
    fitted.prepareCascade ();
  }
  catch (const ModelError &e)
  {
    throw std::invalid_argument (std::string ("PatchClassifier::fitCascade: ") + e.what ());
  }
  *this = std::move (fitted);
}

void
PatchClassifier::prepareCascade ()
{
  stage_fragments_.clear ();
  if (cascade_.empty ())
    return;
  std::size_t rounds = 0;
  for (const ClassTrees &t : trees_)
  {
    if (t.stumps.empty ())
      throw ModelError ("a cascade over trees deeper than stumps");
    rounds = std::max (rounds, t.stumps.size ());
  }
  checkCascade (cascade_, trees_.size (), rounds);
  const std::size_t fragments = dictionary_.size (), stages = cascade_.stage_ends.size ();
  std::vector<char> done (fragments, 0);
  std::vector<std::vector<int>> lists (stages + 1);
  for (std::size_t s = 0; s <= stages; ++s)
  {
    const std::size_t begin = s == 0 ? 0 : static_cast<std::size_t> (cascade_.stage_ends[s - 1]);
    const std::size_t end = s < stages ? static_cast<std::size_t> (cascade_.stage_ends[s]) : rounds;
    for (const ClassTrees &t : trees_)
      for (std::size_t r = begin; r < end && r < t.stumps.size (); ++r)
      {
        const std::size_t f = static_cast<std::size_t> (t.stumps[r].feature);
        if (f < fragments && !done[f])  // auxiliary features are given, not computed
        {
          done[f] = 1;
          lists[s].push_back (static_cast<int> (f));
        }
      }
    std::sort (lists[s].begin (), lists[s].end ());
  }
  stage_fragments_ = std::move (lists);
}

void
PatchClassifier::setPatchGeometry (const PatchGeometry &geometry)
{
  if (geometry.size != geometry_.size)
    throw std::invalid_argument ("PatchClassifier::setPatchGeometry: size " + std::to_string (geometry.size) +
                                 ", the model was trained on " + std::to_string (geometry_.size));
  if (!(std::isfinite (geometry.extent) && geometry.extent > 0.f && std::isfinite (geometry.clamp) &&
        geometry.clamp > 0.f))
    throw std::invalid_argument ("PatchClassifier::setPatchGeometry: extent and clamp must be finite and positive");
  geometry_ = geometry;
}

void
PatchClassifier::save (const std::string &path, const nlohmann::json &metadata) const
{
  if (!trained ())
    throw std::logic_error ("PatchClassifier::save: the classifier is not trained");
  // ASCII only (non-ASCII escaped as \uXXXX), invalid UTF-8 replaced rather than thrown.
  const std::string text = metadata.dump (-1, ' ', true, nlohmann::json::error_handler_t::replace);

  cv::FileStorage fs (".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  fs.write ("format", std::string (kFormatName));
  // A patch-only classifier stays a version-1 file, readable by earlier agex releases.
  fs << "format_version" << (auxiliary_names_.empty () ? 1 : kFormatVersion);
  fs << "classes" << classes ();
  fs << "patch" << "{";
  fs << "size" << geometry_.size << "extent" << geometry_.extent << "clamp" << geometry_.clamp;
  fs << "}";
  fs << "training" << "{";
  fs.write ("boost_type", std::string ("GentleAdaboost"));
  fs << "weak_count" << params_.weak_count << "weight_trim_rate" << params_.weight_trim_rate << "max_depth" << 1;
  fs << "}";
  fs << "metadata" << "[";
  for (std::size_t i = 0; i < text.size (); i += kMetadataChunk)
    fs.write (cv::String (), kChunkFence + text.substr (i, kMetadataChunk) + kChunkFence);
  fs << "]";
  fs << "dictionary" << "{";
  dictionary_.write (fs);
  fs << "}";
  if (!auxiliary_names_.empty ())
  {
    fs << "auxiliary_features" << "[";
    for (const auto &name : auxiliary_names_)
      fs.write (cv::String (), kChunkFence + name + kChunkFence);
    fs << "]";
  }
  fs << "boosters" << "[";
  for (std::size_t c = 0; c < boosters_.size (); ++c)
  {
    fs << "{";
    fs << "class" << static_cast<int> (c);
    boosters_[c]->write (fs);
    fs << "}";
  }
  fs << "]";
  if (!cascade_.empty ())
  {
    // Doubles: each float threshold reads back exactly.
    fs << "cascade" << "{";
    fs << "stage_ends" << "[:";
    for (const int e : cascade_.stage_ends)
      fs << e;
    fs << "]";
    fs << "levels" << "[:";
    for (const float l : cascade_.levels)
      fs << static_cast<double> (l);
    fs << "]";
    fs << "miss_rates" << "[:";
    for (const float m : cascade_.miss_rates)
      fs << static_cast<double> (m);
    fs << "]";
    fs << "thresholds" << "[:";
    for (const float t : cascade_.thresholds)
      fs << static_cast<double> (t);
    fs << "]";
    fs << "}";
  }
  // Written last: a file cut anywhere before it is recognisably truncated.
  fs.write ("end", std::string (kFormatName));
  agex::writeFileAtomic (path, fs.releaseAndGetString ());
}

PatchClassifier
PatchClassifier::load (const std::string &path)
{
  const std::string bytes = readWholeFile (path);
  if (bytes.empty ())
    throw ModelError (path + ": empty file, not an agex model");
  if (bytes.compare (0, 5, "%YAML") != 0)
    throw ModelError (path + ": not an agex model (not a YAML file)");
  std::size_t deep_line = 0;
  if (yamlNestingBound (bytes, kMaxModelNesting, &deep_line) > kMaxModelNesting)
    throw ModelError (path + ":" + std::to_string (deep_line) + ": nested more than " +
                      std::to_string (kMaxModelNesting) + " levels deep; not an agex model (damaged or hostile)");
  // OpenCV's parser decodes !!binary (base64) nodes, and loops for minutes on some damaged
  // ones (a 238-byte file found by the model fuzzer); agex writes none.
  const std::size_t binary = bytes.find ("!!binary");
  if (binary != std::string::npos)
    throw ModelError (path + ":" + std::to_string (1 + std::count (bytes.begin (), bytes.begin () + binary, '\n')) +
                      ": base64 data (!!binary), which agex models never hold; not an agex model (damaged or hostile)");

  cv::FileStorage fs;
  try
  {
    fs.open (bytes, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  }
  catch (const cv::Exception &e)
  {
    throw ModelError (path + ": damaged model file (truncated or not valid YAML: " + e.err + ")");
  }
  catch (const std::exception &e)
  {
    // OpenCV's parser lets a few standard exceptions through on damaged input.
    throw ModelError (path + ": damaged model file (truncated or not valid YAML: " + e.what () + ")");
  }
  if (!fs.isOpened ())
    throw ModelError (path + ": damaged model file (cannot be parsed)");
  // FileStorage::operator[] throws on a document that is not a mapping.
  if (!fs.root ().isMap ())
    throw ModelError (path + ": not an agex model (no 'format: " + kFormatName + "')");

  const cv::FileNode format = fs["format"];
  if (format.empty () || !format.isString () || static_cast<std::string> (format) != kFormatName)
    throw ModelError (path + ": not an agex model (no 'format: " + kFormatName + "')");
  const cv::FileNode version = fs["format_version"];
  if (version.empty () || !version.isInt ())
    throw ModelError (path + ": damaged model file (missing or invalid format_version)");
  if (static_cast<int> (version) != 1 && static_cast<int> (version) != kFormatVersion)
    throw ModelError (path + ": model format version " + std::to_string (static_cast<int> (version)) +
                      " is not supported (this build reads " + std::to_string (kFormatVersion) + ")");
  const cv::FileNode end = fs["end"];
  if (end.empty () || !end.isString () || static_cast<std::string> (end) != kFormatName)
    throw ModelError (path + ": damaged model file (truncated: no end marker)");

  PatchClassifier model;
  try
  {
    const int classes = readInt (fs.root (), "classes");
    if (classes < 1)
      throw ModelError ("classes must be at least 1");

    const cv::FileNode patch = fs["patch"];
    if (patch.empty () || !patch.isMap ())
      throw ModelError ("missing 'patch'");
    model.geometry_.size = readInt (patch, "size");
    model.geometry_.extent = static_cast<float> (readReal (patch, "extent"));
    model.geometry_.clamp = static_cast<float> (readReal (patch, "clamp"));
    if (model.geometry_.size < 1 || model.geometry_.size > agex::DepthPatch::kMaxSize)
      throw ModelError ("patch size " + std::to_string (model.geometry_.size) + " outside 1.." +
                        std::to_string (agex::DepthPatch::kMaxSize));
    if (!std::isfinite (model.geometry_.extent) || !std::isfinite (model.geometry_.clamp))
      throw ModelError ("patch extent or clamp not finite");

    const cv::FileNode training = fs["training"];
    if (training.empty () || !training.isMap ())
      throw ModelError ("missing 'training'");
    model.params_.weak_count = readInt (training, "weak_count");
    model.params_.weight_trim_rate = readReal (training, "weight_trim_rate");

    const cv::FileNode meta = fs["metadata"];
    if (meta.empty () || !meta.isSeq ())
      throw ModelError ("missing 'metadata'");
    std::string text;
    for (cv::FileNodeIterator it = meta.begin (); it != meta.end (); ++it)
    {
      if (!(*it).isString ())
        throw ModelError ("invalid metadata chunk");
      const std::string chunk = static_cast<std::string> (*it);
      if (chunk.size () < 2 || chunk.front () != kChunkFence || chunk.back () != kChunkFence)
        throw ModelError ("invalid metadata chunk");
      text.append (chunk, 1, chunk.size () - 2);
    }
    try
    {
      // nlohmann's parser does not recurse, but printing the result does: bound it here.
      constexpr int kMaxMetadataDepth = 64;
      model.metadata_ = nlohmann::json::parse (text, [] (int depth, nlohmann::json::parse_event_t, nlohmann::json &) {
        if (depth > kMaxMetadataDepth)
          throw ModelError ("metadata nested more than " + std::to_string (kMaxMetadataDepth) + " levels deep");
        return true;
      });
    }
    catch (const nlohmann::json::exception &e)
    {
      throw ModelError (std::string ("metadata is not JSON: ") + e.what ());
    }

    model.dictionary_.read (fs["dictionary"]);
    if (model.dictionary_.patchSize () != model.geometry_.size)
      throw ModelError ("the dictionary's patch size does not match the patch size");
    if (model.dictionary_.size () == 0)
      throw ModelError ("the dictionary is empty");
    for (const Fragment &f : model.dictionary_.fragments ())
      if (f.cls >= classes)
        throw ModelError ("a fragment of class " + std::to_string (f.cls) + " in a " + std::to_string (classes) +
                          "-class model");
    model.params_.dictionary = model.dictionary_.params ();

    const cv::FileNode auxiliary = fs["auxiliary_features"];
    if (!auxiliary.empty ())
    {
      if (static_cast<int> (version) < 2 || !auxiliary.isSeq () || auxiliary.size () > kMaxAuxiliaryFeatures)
        throw ModelError ("invalid auxiliary_features");
      for (cv::FileNodeIterator it = auxiliary.begin (); it != auxiliary.end (); ++it)
      {
        if (!(*it).isString ())
          throw ModelError ("invalid auxiliary feature name");
        const std::string name = static_cast<std::string> (*it);
        if (name.size () < 2 || name.size () > 130 || name.front () != kChunkFence || name.back () != kChunkFence)
          throw ModelError ("invalid auxiliary feature name");
        model.auxiliary_names_.push_back (name.substr (1, name.size () - 2));
      }
    }
    const cv::FileNode boosters = fs["boosters"];
    if (boosters.empty () || !boosters.isSeq () || static_cast<int> (boosters.size ()) != classes)
      throw ModelError ("need " + std::to_string (classes) + " boosters");
    const int features = static_cast<int> (model.dictionary_.size () + model.auxiliary_names_.size ());
    int c = 0;
    for (cv::FileNodeIterator it = boosters.begin (); it != boosters.end (); ++it, ++c)
    {
      const std::string where = "booster " + std::to_string (c) + ": ";
      const cv::FileNode node = *it;
      try
      {
        checkBoosterNode (node, features);
        if (readInt (node, "class") != c)
          throw ModelError ("boosters out of order");
        cv::Ptr<cv::ml::Boost> boost = cv::ml::Boost::create ();
        boost->read (node);
        if (!boost->isTrained ())
          throw ModelError ("fails to load");
        model.boosters_.push_back (boost);
      }
      catch (const ModelError &e)
      {
        throw ModelError (where + e.what ());
      }
      catch (const cv::Exception &e)
      {
        throw ModelError (where + "fails to load (" + e.err + ")");
      }
    }
    model.prepare ();
    const cv::FileNode cascade = fs["cascade"];
    if (!cascade.empty ())
    {
      if (!cascade.isMap ())
        throw ModelError ("invalid cascade");
      const auto numbers = [&cascade] (const char *key, std::size_t most) {
        const cv::FileNode seq = cascade[key];
        if (seq.empty () || !seq.isSeq () || seq.size () > most)
          throw ModelError (std::string ("cascade.") + key + ": need 1 to " + std::to_string (most) + " numbers");
        std::vector<double> values;
        for (cv::FileNodeIterator it = seq.begin (); it != seq.end (); ++it)
        {
          if (!(*it).isReal () && !(*it).isInt ())
            throw ModelError (std::string ("cascade.") + key + ": not a number");
          values.push_back (static_cast<double> (*it));
        }
        return values;
      };
      for (const double e : numbers ("stage_ends", kMaxCascadeStages))
      {
        if (!(e >= 1.0 && e <= 1e6) || e != std::floor (e))
          throw ModelError ("cascade.stage_ends: not a round count");
        model.cascade_.stage_ends.push_back (static_cast<int> (e));
      }
      for (const double l : numbers ("levels", kMaxCascadeLevels))
        model.cascade_.levels.push_back (static_cast<float> (std::max (-2.0, std::min (2.0, l))));
      // Without miss rates (the first cascades): direct backward pruning alone.
      if (cascade["miss_rates"].empty ())
        model.cascade_.miss_rates = {0.f};
      else
        for (const double m : numbers ("miss_rates", kMaxCascadeLevels))
          model.cascade_.miss_rates.push_back (static_cast<float> (std::max (-2.0, std::min (2.0, m))));
      const std::size_t expected = model.cascade_.miss_rates.size () * model.cascade_.levels.size () *
                                   static_cast<std::size_t> (classes) * model.cascade_.stage_ends.size ();
      for (const double t : numbers ("thresholds", expected))
        model.cascade_.thresholds.push_back (
            std::fabs (t) <= static_cast<double> (-kNeverBelow) ? static_cast<float> (t)
                                                                : std::numeric_limits<float>::infinity ());
      model.cascade_.classes = classes;
      model.prepareCascade ();
    }
    // What the model was trained with (the file keeps the cascade, not the parameters).
    model.params_.cascade_stage_ends = model.cascade_.stage_ends;
    model.params_.cascade_levels = model.cascade_.levels;
    model.params_.cascade_miss_rates = model.cascade_.miss_rates;
  }
  catch (const ModelError &e)
  {
    throw ModelError (path + ": damaged model file (" + e.what () + ")");
  }
  catch (const cv::Exception &e)
  {
    throw ModelError (path + ": damaged model file (" + e.err + ")");
  }
  catch (const std::exception &e)
  {
    throw ModelError (path + ": damaged model file (" + e.what () + ")");
  }
  return model;
}
}  // namespace agex

#pragma once
// MakeHuman's macro shape targets (../shared/data/makehuman/targets/macrodetails) and
// the weights MakeHuman 1.1 blends them with (doc/synthetic.md, "Body shapes").
#include <agex/simulation/body_shape.h>

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

namespace agex
{
/** \brief The macro targets of a MakeHuman directory, blended as MakeHuman 1.1's macro
  * modifiers blend them (apps/humanmodifier.py, MacroModifier and getTargetWeights).
  *
  * A target's weight is the product of the values of the macro categories its file name
  * names, e.g. universal-female-young-maxmuscle-minweight: female x young x maxmuscle x
  * minweight. The values follow MakeHuman's human.py: female = 1 - gender, male =
  * gender; young = 1 - old, old = 2 age - 1 (age >= 0.5; baby and child below); for
  * muscle, weight and height: min = max(0, 1 - 2v), max = max(0, 2v - 1), average = 1 -
  * min - max; the ethnic values as they are. Words of a name that are no category (and
  * the folders) form its group ("macrodetails", "macrodetails-universal",
  * "macrodetails-height"), which must be one the modifiers file controls by macro
  * variables. */
class MakeHumanTargets
{
public:
  struct Target
  {
    std::string file;                   ///< path, for messages
    std::string group;                  ///< e.g. "macrodetails-height"
    std::vector<std::string> factors;   ///< category words of the name, e.g. "female", "maxheight"
    std::vector<int> vertices;          ///< into base.obj's whole vertex list (0-based)
    std::vector<Eigen::Vector3f> offsets;  ///< per listed vertex, decimetres (the mesh's units)
  };

  /** At most this many target files and this many bytes per file (the largest shipped
    * target is about 0.5 MB). */
  static constexpr int kMaxTargets = 512;
  static constexpr std::size_t kMaxFileBytes = 64u << 20;
  /** The largest offset a target may give a vertex, decimetres (2 m). */
  static constexpr double kMaxOffset = 20.0;

  /** \brief Reads modifiers/modeling_modifiers.json and every .target file under
    * targets/macrodetails (one folder deep) of a MakeHuman directory, for a base mesh of
    * vertex_count vertices.
    * \throws HumanMeshError naming the file (and line) and the problem: a vertex index
    * out of range or listed twice, a number that is not finite or larger than
    * kMaxOffset, an unknown group, too many or too large files, missing groups */
  static MakeHumanTargets load (const std::string &directory, std::size_t vertex_count);

  const std::vector<Target> &targets () const { return targets_; }
  std::size_t vertexCount () const { return vertex_count_; }

  /** The weight of one category word for a shape (MakeHuman's <word>Val), e.g. "male". */
  static double factor (const std::string &word, const BodyShape &shape);
  /** Each target's weight for a shape, indexed like targets().
    * \throws HumanMeshError if the shape is not valid (BodyShape::problem) */
  std::vector<double> weights (const BodyShape &shape) const;
  /** \brief The blended offset of every vertex of the base mesh, metres.
    * \throws HumanMeshError if the shape is not valid */
  std::vector<Eigen::Vector3d> offsets (const BodyShape &shape) const;

private:
  std::vector<Target> targets_;
  std::size_t vertex_count_ = 0;
};
}  // namespace agex

#pragma once
// The processes of one run: a single process, or the ranks of an MPI job (mpirun -n N) that
// share its frames. Batch runs (batch_runs.h) speak to it; only process_group.cpp knows MPI,
// so that agex builds and runs as before without it.

#include <memory>
#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** \brief The processes of a run and the few collective steps a batch run needs. Every
  * process calls the collective functions in the same order. */
class ProcessGroup
{
public:
  virtual ~ProcessGroup () = default;
  virtual int rank () const { return 0; }
  virtual int size () const { return 1; }
  /** Whether several processes share the run. */
  bool distributed () const { return size () > 1; }
  /** Rank 0 gets every rank's text in rank order; the others get an empty vector. */
  virtual std::vector<std::string> gather (const std::string &mine) { return {mine}; }
  /** Every rank gets rank 0's text. */
  virtual std::string broadcast (const std::string &from_rank_0) { return from_rank_0; }
};

/** \brief The group this process belongs to. Under mpirun (OpenMPI's, or any PMI/PMIx
  * launcher), and built with MPI, MPI is initialised here and finalised when the group is
  * destroyed: create it first in main and keep it to the end.
  * \throws std::runtime_error when started by an MPI launcher with more than one process in
  *         a build without MPI (every process would do every frame) */
std::unique_ptr<ProcessGroup> joinProcessGroup (int &argc, char **&argv);

/** Whether this build can run under mpirun. */
bool mpiSupported ();
}  // namespace apps
}  // namespace agex

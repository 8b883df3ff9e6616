#include <agex/apps/process_group.h>

#include <cstdlib>
#include <limits>
#include <stdexcept>

#ifdef AGEX_WITH_MPI
// The C API only: no C++ bindings (deprecated, and a library of their own).
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace agex
{
namespace apps
{
namespace
{
/** The number of processes an MPI launcher started, from its environment; 0 if none did. */
int
launchedProcesses ()
{
  for (const char *name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"})
    if (const char *value = std::getenv (name))
      return std::atoi (value);
  return std::getenv ("PMIX_RANK") ? 2 : 0;  // PMIx without a size: assume a real job
}

#ifdef AGEX_WITH_MPI
class MpiGroup : public ProcessGroup
{
public:
  MpiGroup (int &argc, char **&argv)
  {
    int provided = 0;
    // Only the main thread speaks MPI; worker threads process frames.
    if (MPI_Init_thread (&argc, &argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
      throw std::runtime_error ("MPI_Init_thread failed");
    MPI_Comm_rank (MPI_COMM_WORLD, &rank_);
    MPI_Comm_size (MPI_COMM_WORLD, &size_);
  }
  ~MpiGroup () override { MPI_Finalize (); }
  int rank () const override { return rank_; }
  int size () const override { return size_; }

  std::vector<std::string> gather (const std::string &mine) override
  {
    int length = static_cast<int> (mine.size ());
    std::vector<int> lengths (rank_ == 0 ? size_ : 0), offsets (lengths.size ());
    MPI_Gather (&length, 1, MPI_INT, lengths.data (), 1, MPI_INT, 0, MPI_COMM_WORLD);
    std::string all;
    if (rank_ == 0)
    {
      std::size_t total = 0;
      for (int r = 0; r < size_; ++r)
      {
        offsets[r] = static_cast<int> (total);
        total += static_cast<std::size_t> (lengths[r]);
      }
      if (total > static_cast<std::size_t> (std::numeric_limits<int>::max ()))
        throw std::runtime_error ("the ranks' results are too large to gather (over 2 GB)");
      all.resize (total);
    }
    MPI_Gatherv (mine.data (), length, MPI_CHAR, all.data (), lengths.data (), offsets.data (), MPI_CHAR, 0,
                 MPI_COMM_WORLD);
    std::vector<std::string> texts;
    for (int r = 0; rank_ == 0 && r < size_; ++r)
      texts.push_back (all.substr (offsets[r], lengths[r]));
    return texts;
  }

  std::string broadcast (const std::string &from_rank_0) override
  {
    unsigned long long length = from_rank_0.size ();
    MPI_Bcast (&length, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
    std::string text = rank_ == 0 ? from_rank_0 : std::string (length, '\0');
    MPI_Bcast (text.data (), static_cast<int> (length), MPI_CHAR, 0, MPI_COMM_WORLD);
    return text;
  }

private:
  int rank_ = 0, size_ = 1;
};
#endif
}  // namespace

bool
mpiSupported ()
{
#ifdef AGEX_WITH_MPI
  return true;
#else
  return false;
#endif
}

std::unique_ptr<ProcessGroup>
joinProcessGroup (int &argc, char **&argv)
{
  const int launched = launchedProcesses ();
#ifdef AGEX_WITH_MPI
  if (launched > 0)
    return std::make_unique<MpiGroup> (argc, argv);
#else
  (void) argc;
  (void) argv;
  if (launched > 1)
    throw std::runtime_error ("started by mpirun with " + std::to_string (launched) +
                              " processes, but this agex was built without MPI, so each would process every "
                              "frame; rebuild with MPI (Debian: libopenmpi-dev) or split the frames with --shard K/N");
#endif
  return std::make_unique<ProcessGroup> ();
}
}  // namespace apps
}  // namespace agex

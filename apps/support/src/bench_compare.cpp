#include <agex/apps/bench_compare.h>

#include <agex/detection/benchmark.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

namespace agex
{
namespace apps
{
namespace
{
/** This process's environment with BUILD/lib first on LD_LIBRARY_PATH, for program
  * BUILD/bin/NAME when BUILD/lib exists: a copied build tree (cp -a build /tmp/before) keeps
  * the RUNPATH of the tree it was built in, and would load that tree's libraries. */
std::vector<std::string>
environmentFor (const std::string &program)
{
  std::vector<std::string> env;
  const char *old_path = nullptr;
  for (char **e = environ; e && *e; ++e)
  {
    if (std::strncmp (*e, "LD_LIBRARY_PATH=", 16) == 0)
      old_path = *e + 16;
    else
      env.emplace_back (*e);
  }
  const std::string bin = program.substr (0, program.find_last_of ('/') == std::string::npos ? 0 : program.find_last_of ('/'));
  const std::string lib = (bin.empty () ? std::string (".") : bin) + "/../lib";
  struct stat st;
  std::string path = stat (lib.c_str (), &st) == 0 && S_ISDIR (st.st_mode) ? lib : std::string ();
  if (old_path && *old_path)
    path += (path.empty () ? "" : ":") + std::string (old_path);
  if (!path.empty ())
    env.push_back ("LD_LIBRARY_PATH=" + path);
  return env;
}

/** Runs program with arguments, its output to log. \return "" when it exited with 0, else what
  * went wrong (its exit status, the signal that ended it, or why it could not start). */
std::string
runProgram (const std::string &program, const std::vector<std::string> &arguments, const std::string &log)
{
  std::vector<std::string> environment = environmentFor (program);
  std::vector<char *> envp;
  for (auto &e : environment)
    envp.push_back (e.data ());
  envp.push_back (nullptr);
  std::vector<char *> argv;
  argv.push_back (const_cast<char *> (program.c_str ()));
  for (const auto &a : arguments)
    argv.push_back (const_cast<char *> (a.c_str ()));
  argv.push_back (nullptr);
  posix_spawn_file_actions_t actions;
  if (posix_spawn_file_actions_init (&actions) != 0)
    return "cannot set up its start";
  int spawned =
      posix_spawn_file_actions_addopen (&actions, STDOUT_FILENO, log.c_str (), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (spawned == 0)
    spawned = posix_spawn_file_actions_adddup2 (&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = 0;
  if (spawned == 0)
    spawned = posix_spawn (&pid, program.c_str (), &actions, nullptr, argv.data (), envp.data ());
  posix_spawn_file_actions_destroy (&actions);
  if (spawned != 0)
    return std::string ("could not start: ") + std::strerror (spawned);
  int status = 0;
  pid_t waited;
  while ((waited = waitpid (pid, &status, 0)) < 0 && errno == EINTR)
  {
  }
  if (waited != pid)
    return std::string ("could not be waited for: ") + std::strerror (errno);
  if (WIFSIGNALED (status))
    return "was ended by signal " + std::to_string (WTERMSIG (status));
  if (!WIFEXITED (status) || WEXITSTATUS (status) != 0)
    return "failed (exit " + std::to_string (WIFEXITED (status) ? WEXITSTATUS (status) : -1) + ")";
  return "";
}

/** The median as agex_bench reports every timing: a sample that was measured. */
double
median (std::vector<double> values)
{
  return summariseTimings (std::move (values)).median;
}

/** Per stage ("total" for the whole frame), the report's median milliseconds. */
std::map<std::string, double>
stageMedians (const std::string &report, const std::string &program)
{
  std::ifstream in (report);
  if (!in)
    throw std::runtime_error (program + " wrote no report " + report);
  nlohmann::json doc;
  try
  {
    doc = nlohmann::json::parse (in);
  }
  catch (const nlohmann::json::exception &e)
  {
    throw std::runtime_error (report + " (of " + program + "): not a JSON report: " + e.what ());
  }
  std::map<std::string, double> medians;
  const auto number = [] (const nlohmann::json &stats) {
    return stats.is_object () && stats.contains ("median") && stats["median"].is_number ();
  };
  if (!doc.is_object () || !doc.contains ("ms_per_frame") || !number (doc["ms_per_frame"]) || !doc.contains ("stages") ||
      !doc["stages"].is_object ())
    throw std::runtime_error (report + " (of " + program + "): not an agex_bench --dataset report");
  medians["total"] = doc["ms_per_frame"]["median"].get<double> ();
  for (const auto &[stage, stats] : doc["stages"].items ())
    if (number (stats))
      medians[stage] = stats["median"].get<double> ();
  return medians;
}
}  // namespace

std::vector<std::string>
forwardedBenchArguments (int argc, char **argv)
{
  static const char *const kOwn[] = {"--compare-with", "--rounds", "--json", "--jobs", "--model", "--passes"};
  std::vector<std::string> kept;
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    bool own = false;
    for (const char *flag : kOwn)
    {
      const std::string f = flag;
      if (a == f)
      {
        own = true;
        ++i;  // its value
        break;
      }
      if (a.rfind (f + "=", 0) == 0)
      {
        own = true;
        break;
      }
    }
    if (!own)
      kept.push_back (a);
  }
  return kept;
}

std::string
otherBenchProgram (const std::string &build_dir)
{
  const std::string program = build_dir + "/bin/agex_bench";
  struct stat st;
  if (stat (program.c_str (), &st) != 0 || !S_ISREG (st.st_mode) || access (program.c_str (), X_OK) != 0)
    throw std::runtime_error ("--compare-with " + build_dir + ": no executable bin/agex_bench in it");
  return program;
}

nlohmann::json
compareBenchBuilds (const BenchComparison &c)
{
  if (c.rounds < 1)
    throw std::runtime_error ("compareBenchBuilds: at least one round");
  std::map<std::string, std::vector<double>> this_ms, other_ms, ratios;
  const std::string programs[2] = {c.this_program, c.other_program};
  for (int round = 0; round < c.rounds; ++round)
  {
    std::map<std::string, double> medians[2];
    for (int turn = 0; turn < 2; ++turn)
    {
      const int which = (round % 2 == 0) ? turn : 1 - turn;  // this first in even rounds
      const std::string stem = c.work_dir + "/round" + std::to_string (round) + (which == 0 ? "_this" : "_other");
      std::vector<std::string> arguments = c.arguments;
      arguments.insert (arguments.end (), {"--model", c.model, "--passes", std::to_string (c.passes), "--jobs", "1",
                                           "--json", stem + ".json"});
      const std::string problem = runProgram (programs[which], arguments, stem + ".log");
      if (!problem.empty ())
        throw std::runtime_error (programs[which] + " " + problem + " (its output: " + stem + ".log)");
      medians[which] = stageMedians (stem + ".json", programs[which]);
    }
    for (const auto &[stage, ms] : medians[0])
    {
      const auto other = medians[1].find (stage);
      if (other == medians[1].end ())
        continue;  // a stage only one build times
      this_ms[stage].push_back (ms);
      other_ms[stage].push_back (other->second);
      if (other->second > 0.0)
        ratios[stage].push_back (ms / other->second);
    }
    std::fprintf (stderr, "  round %d/%d\n", round + 1, c.rounds);
  }
  nlohmann::json stages = nlohmann::json::object (), total;
  std::printf ("this build against %s, %d alternating round%s, one thread, medians:\n", c.other_program.c_str (),
               c.rounds, c.rounds == 1 ? "" : "s");
  std::printf ("  %-14s %10s %10s %8s\n", "stage", "this ms", "other ms", "ratio");
  for (const auto &[stage, values] : this_ms)
  {
    const nlohmann::json entry = {{"this_ms", median (values)},
                                  {"other_ms", median (other_ms[stage])},
                                  {"ratio", median (ratios[stage])}};
    if (stage == "total")
      total = entry;
    else
      stages[stage] = entry;
  }
  for (const auto &[stage, entry] : stages.items ())
    std::printf ("  %-14s %10.3f %10.3f %8.3f\n", stage.c_str (), entry["this_ms"].get<double> (),
                 entry["other_ms"].get<double> (), entry["ratio"].get<double> ());
  if (!total.is_null ())
    std::printf ("  %-14s %10.3f %10.3f %8.3f\n", "total", total["this_ms"].get<double> (),
                 total["other_ms"].get<double> (), total["ratio"].get<double> ());
  return {{"compare_with", c.other_program}, {"rounds", c.rounds}, {"stages", stages}, {"total", total}};
}
}  // namespace apps
}  // namespace agex

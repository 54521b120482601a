// simulate: the batch front end. Runs one scene faster than real time, without ROS, and writes
// its trajectory as CSV (issue 2, "Batch simulator"; usage and contract in doc/simulate.md).
//
//   simulate --config FILE.yaml [--set key=value]... [--duration SECONDS]
//            [--output-rate HZ] [--output FILE.csv]
//
// The CSV starts with one comment line, "# integrator: <what ran and why>".
// Exit codes: 0 success (also when a validity event ends the run early), 1 runtime error
// unrelated to the input (e.g. the output cannot be written), 2 bad input (options, YAML,
// keys, values), 3 the run needs more integration steps than --max-steps allows (the rows up to
// there are written to stdout or a stream, a file output is not created). On exit code 2 nothing is written; a file output appears only complete; a FIFO
// or character device given as --output is written to, never replaced; a signal that ends the
// run removes the temporary file (issue 19).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "spinning_top/case_run.hpp"
#include "spinning_top/config.hpp"
#include "spinning_top/integrator_registry.hpp"
#include "spinning_top/scene_file.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace {

constexpr int kExitRuntimeError = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitStepBudget = 3;
/// Budget steps one run may take unless --max-steps says otherwise (work_budget.hpp: work counted
/// alike on every method, 0.1-1 us of CPU per budget step, bench/budget_time.cpp): at most about
/// 100 s of CPU, so that an absurd request (a fast spin over a long duration, a tiny step) ends
/// with a clear error instead of hours of CPU.
constexpr double kDefaultMaxSteps = 1e8;
constexpr double kDefaultDuration = 10.0;    // [s]
constexpr double kDefaultOutputRate = 100.0;  // [Hz]
// More rows than this is a typo (and more than a disk holds at ~300 bytes a row).
constexpr double kMaxOutputIntervals = 1e9;

/// The CSV's numeric columns, in order: the header's names, each row's values (17 significant
/// digits) and --help's description of them. The text column `event` ends every row.
struct CsvColumn {
  const char* name;
  const char* description;
  double (*value)(double t, const Snapshot& s);
};
const CsvColumn kCsvColumns[] = {
    {"t", "[s] simulated time", [](double t, const Snapshot&) { return t; }},
    {"qw", "the attitude q (body -> world), a unit quaternion: w", [](double, const Snapshot& s) { return s.attitude.w(); }},
    {"qx", "x", [](double, const Snapshot& s) { return s.attitude.x(); }},
    {"qy", "y", [](double, const Snapshot& s) { return s.attitude.y(); }},
    {"qz", "z", [](double, const Snapshot& s) { return s.attitude.z(); }},
    {"gx", "[m] G's position: x", [](double, const Snapshot& s) { return s.outputs.center_of_mass.x(); }},
    {"gy", "[m] y", [](double, const Snapshot& s) { return s.outputs.center_of_mass.y(); }},
    {"gz", "[m] z", [](double, const Snapshot& s) { return s.outputs.center_of_mass.z(); }},
    {"px", "[m] the tip P: x", [](double, const Snapshot& s) { return s.outputs.contact_point.x(); }},
    {"py", "[m] y", [](double, const Snapshot& s) { return s.outputs.contact_point.y(); }},
    {"pz", "[m] the tip's height above the floor (0 on it)", [](double, const Snapshot& s) { return s.outputs.contact_point.z(); }},
    {"normal_force", "[N] R, the floor's normal force", [](double, const Snapshot& s) { return s.outputs.normal_force; }},
    {"contact_force_x", "[N] the horizontal floor force on the tip (pivot reaction, friction, or 0): x",
     [](double, const Snapshot& s) { return s.outputs.contact_force.x(); }},
    {"contact_force_y", "[N] y", [](double, const Snapshot& s) { return s.outputs.contact_force.y(); }},
    {"energy", "[J] E", [](double, const Snapshot& s) { return s.outputs.energy; }},
};
constexpr const char* kPhaseColumn = "phase";
constexpr const char* kEventColumn = "event";

/// The CSV header: kCsvColumns' names, then the text columns phase and event.
std::string csv_header() {
  std::string header;
  for (const CsvColumn& column : kCsvColumns) header += std::string(column.name) + ",";
  return header + kPhaseColumn + "," + kEventColumn;
}

/// A path as a message shows it: whole up to 160 characters, else its start and end.
std::string shown(const std::string& path) {
  std::string text = path.size() <= 160 ? path : path.substr(0, 40) + "..." + path.substr(path.size() - 117);
  for (char& c : text)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';  // one line
  return text;
}

/// Bad input: reported on stderr with exit code 2 before anything is written.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Options {
  bool help = false;
  std::string config_path;
  std::vector<std::pair<std::string, std::string>> overrides;  ///< --set key=value, in order
  double duration = kDefaultDuration;
  double output_rate = kDefaultOutputRate;
  std::string output_path;  ///< empty: stdout
  double max_steps = kDefaultMaxSteps;
};

/// The run needed more integration steps than --max-steps.
class StepBudgetExceeded : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

void print_help(std::ostream& out) {
  out << "Usage: simulate --config FILE.yaml [--set key=value]... [--duration SECONDS]\n"
         "                [--output-rate HZ] [--output FILE.csv] [--max-steps N]\n"
         "\n"
         "Runs one spinning-top scene without ROS, faster than real time, and writes its\n"
         "trajectory as CSV (SI units, REP-103).\n"
         "\n"
         "Options:\n"
         "  --config FILE.yaml   scene file (required), e.g. config/fixed_tip.yaml\n"
         "  --set key=value      overrides one key of the scene file (repeatable; the last wins)\n"
         "  --duration SECONDS   simulated time to run, > 0 and at most 1e9 (default 10)\n"
         "  --output-rate HZ     output rows per simulated second, > 0 (default 100)\n"
         "  --output FILE.csv    output file (default and '-': stdout). A new or regular file is\n"
         "                       written to a temporary file beside it and renamed, so it appears\n"
         "                       only when complete; a FIFO or character device (also through a\n"
         "                       symbolic link) is written to directly, never replaced; a\n"
         "                       directory or any other kind of file is refused. An existing\n"
         "                       file keeps its mode and its hard links; a read-only one and\n"
         "                       the --config file are refused\n"
         "  --max-steps N        integration steps the run may take, a whole number >= 1\n"
         "                       (default 1e8, ~3 min of CPU); a run that needs more stops\n"
         "                       with exit code 3 rather than computing for hours\n"
         "  --help               this text\n"
         "Options also take the form --option=value.\n"
         "\n"
         "Scene file keys (the node's private parameters). Nested YAML maps flatten with '/':\n"
         "  initial: {tilt: 0.3}  is the key  initial/tilt. Required keys must be in the file\n"
         "(or given with --set); the others default as shown. Unknown keys are errors.\n"
         "A scene file is a regular file of at most 1 MiB without anchors, aliases or tags;\n"
         "its numbers are unquoted, in forms YAML 1.1 (rosparam) and 1.2 read alike: 10,\n"
         "0.5, 4.0e-5 (not 010, 1e5 or 5e-5; doc/simulate.md, \"What a scene file may be\").\n"
         "\n";
  std::size_t key_width = 3, unit_width = 4, default_width = 7;
  for (const ParameterSpec& spec : parameter_specs()) {
    key_width = std::max(key_width, std::strlen(spec.key));
    unit_width = std::max(unit_width, std::strlen(spec.unit));
    default_width = std::max(default_width, spec.default_value.size());
  }
  auto pad = [&out](const std::string& text, std::size_t width) {
    out << text << std::string(width + 2 - text.size(), ' ');
  };
  out << "  ";
  pad("key", key_width);
  pad("unit", unit_width);
  pad("default", default_width);
  pad("required", 8);
  out << "description\n";
  for (const ParameterSpec& spec : parameter_specs()) {
    out << "  ";
    pad(spec.key, key_width);
    pad(*spec.unit ? spec.unit : "-", unit_width);
    pad(spec.default_value, default_width);
    pad(spec.required_in_file ? "yes" : "no", 8);
    out << spec.description << "\n";
  }
  out << "\n"
         "Integrators (values of the integrator key; doc/integrators.md):\n";
  std::size_t name_width = 4, scenes_width = 6, kind_width = 4;
  for (const IntegratorInfo& row : integrator_registry()) {
    name_width = std::max(name_width, std::strlen(row.name));
    scenes_width = std::max(scenes_width, row.scene_names().size());
    kind_width = std::max(kind_width, std::strlen(to_string(row.kind)));
  }
  out << "  ";
  pad("name", name_width);
  pad("scenes", scenes_width);
  pad("kind", kind_width);
  out << "description\n";
  for (const IntegratorInfo& row : integrator_registry()) {
    out << "  ";
    pad(row.name, name_width);
    pad(row.scene_names(), scenes_width);
    pad(to_string(row.kind), kind_width);
    out << row.help << "\n";
  }
  out << "\n"
         "auto, the default, runs what its row says; the states exact refuses are a few degenerate ones,\n"
         "e.g. an axis vertical while it moves, or g = 0 on the frictionless floor. The output's first\n"
         "line says which method ran and why.\n"
         "\n"
         "Output: a comment naming the integrator that ran, e.g.\n"
         "  # integrator: auto: exact: closed form, nutation period 0.058 s, 9 Fourier terms\n"
         "  # integrator: auto: dop853, tolerance 1e-12 (exact refused: <its reason>)\n"
         "  # integrator: auto: radau9, tolerance 1e-13 (stiff: friction rate k (1/m + h^2/A) 2e+06 1/s > 30 x\n"
         "    fastest motion 225 rad/s)\n"
         "then the CSV header\n"
         "  "
      << csv_header()
      << "\n"
         "then one row per output instant t_i = i / rate from t = 0 to the duration inclusive (a\n"
         "last row at t = duration when it is not a multiple of 1/rate), values with 17\n"
         "significant digits:\n";
  std::size_t column_width = std::strlen(kEventColumn);
  for (const CsvColumn& column : kCsvColumns) column_width = std::max(column_width, std::strlen(column.name));
  for (const CsvColumn& column : kCsvColumns) {
    out << "  ";
    pad(column.name, column_width);
    out << column.description << "\n";
  }
  out << "  ";
  pad(kPhaseColumn, column_width);
  out << "contact | flight | skim (doc/spec/HYBRID.md)\n";
  out << "  ";
  pad(kEventColumn, column_width);
  out << "empty; lift_off | take_off | landing on a transition's own row, at its time (the run\n"
         "  goes on; with after_lift_off: stop, lift_off ends it); fallen | non_finite |\n"
         "  energy_drift | lift_off on the last row when the run ends there\n"
         "\n"
         "Exit codes: 0 success (also when an event ends the run early), 1 runtime error\n"
         "(e.g. the output cannot be written), 2 bad input (nothing written), 3 the run needs\n"
         "more than --max-steps integration steps.\n";
}

double parse_option_number(const std::string& option, const std::string& text) {
  double value = 0.0;
  try {
    value = parse_number(option, text);
  } catch (const InvalidParameter& e) {
    throw UsageError(e.what());
  }
  if (!std::isfinite(value) || !(value > 0.0))
    throw UsageError(option + ": must be a finite number > 0, got '" + brief_text(text) + "'");
  return value;
}

Options parse_options(int argc, char** argv) {
  Options options;
  bool seen_duration = false, seen_rate = false, seen_output = false, seen_config = false, seen_max_steps = false;
  for (int i = 1; i < argc; ++i) {
    std::string name = argv[i];
    if (name == "--help" || name == "-h") {
      options.help = true;
      return options;
    }
  }
  for (int i = 1; i < argc; ++i) {
    std::string name = argv[i];
    std::string value;
    bool has_value = false;
    if (name.rfind("--", 0) != 0)
      throw UsageError("unexpected argument '" + brief_text(name) + "' (options start with --)");
    const std::size_t equals = name.find('=');
    if (equals != std::string::npos) {
      value = name.substr(equals + 1);
      name = name.substr(0, equals);
      has_value = true;
    }
    if (name != "--config" && name != "--set" && name != "--duration" && name != "--output-rate" &&
        name != "--output" && name != "--max-steps")
      throw UsageError("unknown option '" + brief_text(name) + "'");
    if (!has_value) {
      if (i + 1 >= argc) throw UsageError(name + ": missing value");
      value = argv[++i];
    }
    auto once = [&name](bool& seen) {
      if (seen) throw UsageError(name + ": given twice");
      seen = true;
    };
    if (name == "--config") {
      once(seen_config);
      if (value.empty()) throw UsageError("--config: empty file name");
      options.config_path = value;
    } else if (name == "--set") {
      const std::size_t split = value.find('=');
      if (split == std::string::npos || split == 0)
        throw UsageError("--set: expected key=value, got '" + brief_text(value) + "'");
      options.overrides.emplace_back(value.substr(0, split), value.substr(split + 1));
    } else if (name == "--duration") {
      once(seen_duration);
      options.duration = parse_option_number(name, value);
      // --duration 1e20 --output-rate 1e-20 ran exact to NaN rows, exit 0 (kMaxSimulatedTime).
      if (!(options.duration <= kMaxSimulatedTime))
        throw UsageError("--duration: must be at most 1e9 s (32 years; beyond it the state loses its meaning), got '" +
                         brief_text(value) + "'");
    } else if (name == "--output-rate") {
      once(seen_rate);
      options.output_rate = parse_option_number(name, value);
    } else if (name == "--max-steps") {
      once(seen_max_steps);
      options.max_steps = parse_option_number(name, value);
      if (!(options.max_steps == std::floor(options.max_steps) && options.max_steps <= 1e15))
        throw UsageError("--max-steps: must be a whole number in [1, 1e15], got '" + brief_text(value) + "'");
    } else {  // --output
      once(seen_output);
      if (value.empty()) throw UsageError("--output: empty file name");
      options.output_path = value;
    }
  }
  if (options.config_path.empty()) throw UsageError("--config FILE.yaml is required");
  if (!(options.duration * options.output_rate <= kMaxOutputIntervals))
    throw UsageError("--duration x --output-rate asks for more than 1e9 output rows");
  return options;
}

/// The file's keys with the --set overrides applied, parsed and validated.
SceneConfig read_scene(const Options& options) {
  ParameterMap values;
  try {
    values = read_scene_file(options.config_path);
  } catch (const SceneFileError& e) {
    throw UsageError(std::string("--config: ") + e.what());
  }
  ParameterMap origin;
  for (const auto& [key, value] : values) origin[key] = "in " + shown(options.config_path);
  for (const auto& [key, value] : options.overrides) {
    values[key] = value;
    origin[brief_text(key)] = "from --set " + brief_text(key + "=" + value);  // as InvalidParameter names it
  }
  try {
    return parse_scene_config(values, /*require_all=*/true);
  } catch (const InvalidParameter& e) {
    const auto it = origin.find(e.parameter());
    throw UsageError(std::string(e.what()) + " (" + (it != origin.end() ? it->second : "in " + shown(options.config_path)) +
                     ")");
  }
}

void write_row(std::FILE* out, double t, const Snapshot& s, Event event) {
  for (const CsvColumn& column : kCsvColumns) std::fprintf(out, "%.17g,", column.value(t, s));
  std::fprintf(out, "%s,%s\n", to_string(s.phase), to_string(event));
}

/// Runs the scene and writes the header comment (the method that runs, and why), the header
/// and every row; returns the event that ended it. Throws StepBudgetExceeded when the run
/// would take more than max_steps integration steps (the rows up to there are written).
Event run(Simulator& simulator, const SampleTimes& times, double max_steps, std::FILE* out) {
  std::fprintf(out, "# integrator: %s\n", simulator.integrator_description().c_str());
  std::fprintf(out, "%s\n", csv_header().c_str());
  // An initial state that already violates the model is an event at t = 0; on an event, time()
  // is the event time, which replaces the scheduled instant.
  const SampledRun sampled =
      sample_run(simulator, times.count(), [&](long long i) { return times.at(i); }, max_steps,
                 StateWhereStepsRunOut::kDrop, [&](double t, const Snapshot& s, Event event) { write_row(out, t, s, event); });
  if (sampled.out_of_steps) {
    char where[160];
    std::snprintf(where, sizeof where, " (at t = %.9g s of %.9g s)", simulator.time(), times.at(times.count() - 1));
    throw StepBudgetExceeded("the run needs more than --max-steps " + std::to_string(static_cast<long>(max_steps)) +
                             " integration steps" + where + " with " + simulator.integrator_description() +
                             ": raise --max-steps, shorten --duration, or loosen step / tolerance");
  }
  return sampled.event;
}

// The temporary output file, removed if a signal ends the run (unlink is async-signal-safe).
char g_temporary_path[4096] = {0};

extern "C" void remove_temporary_and_exit(int signal_number) {
  if (g_temporary_path[0] != '\0') unlink(g_temporary_path);
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

/// Where --output writes, decided by what the path is now (a symbolic link by its target).
struct OutputTarget {
  enum class Kind { kStdout, kReplaceFile, kStream } kind = Kind::kStdout;
  std::string path;  ///< the file to replace or to stream into (a link's target)
};

/// A new path or a regular file: replaced atomically (temporary file and rename). A FIFO or a
/// character device (/dev/null, a terminal): streamed into, since renaming a regular file onto
/// it would replace the device node itself (as root, --output /dev/null would have replaced the
/// system's /dev/null). A directory or any other kind: refused (UsageError: exit 2).
OutputTarget output_target(const std::string& path) {
  OutputTarget target;
  if (path.empty() || path == "-") return target;
  struct stat st {};
  if (lstat(path.c_str(), &st) != 0) {
    if (errno != ENOENT) throw UsageError("--output: cannot inspect '" + shown(path) + "': " + std::strerror(errno));
    target.kind = OutputTarget::Kind::kReplaceFile;  // a new file (a missing directory fails later, exit 1)
    target.path = path;
    return target;
  }
  target.path = path;
  if (S_ISLNK(st.st_mode)) {
    // Replace or stream into what the link points to; renaming onto the link would replace it.
    char* resolved = realpath(path.c_str(), nullptr);
    if (resolved == nullptr)
      throw UsageError("--output: '" + shown(path) + "' is a symbolic link that does not resolve: " + std::strerror(errno));
    target.path = resolved;
    std::free(resolved);
    if (stat(target.path.c_str(), &st) != 0)
      throw UsageError("--output: cannot inspect '" + target.path + "': " + std::strerror(errno));
  }
  if (S_ISREG(st.st_mode)) {
    target.kind = OutputTarget::Kind::kReplaceFile;
  } else if (S_ISFIFO(st.st_mode) || S_ISCHR(st.st_mode)) {
    target.kind = OutputTarget::Kind::kStream;
  } else if (S_ISDIR(st.st_mode)) {
    throw UsageError("--output: '" + shown(path) + "' is a directory; give a file name");
  } else {
    throw UsageError("--output: '" + shown(path) + "' is neither a regular file, a FIFO nor a character device");
  }
  return target;
}

/// Closes an output stream, throwing if a write or the close failed (a full disk shows only
/// there); `file` is null afterwards either way.
void close_checked(std::FILE*& file, const std::string& name) {
  const bool write_failed = std::ferror(file) != 0;
  const int close_status = std::fclose(file);
  file = nullptr;
  if (write_failed || close_status != 0) throw std::runtime_error("cannot write '" + name + "': " + std::strerror(errno));
}

/// Writes straight into a FIFO or a character device (no temporary file, no rename). Opened
/// without O_CREAT, so a path that has meanwhile disappeared is not created as a regular file.
class StreamOutput {
 public:
  explicit StreamOutput(const std::string& path) : path_(path) {
    const int fd = open(path.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
    if (fd < 0) throw std::runtime_error("--output: cannot open '" + shown(path) + "': " + std::strerror(errno));
    file_ = fdopen(fd, "w");
    if (file_ == nullptr) {
      close(fd);
      throw std::runtime_error("cannot open '" + shown(path) + "': " + std::strerror(errno));
    }
  }
  ~StreamOutput() {
    if (file_ != nullptr) std::fclose(file_);
  }
  StreamOutput(const StreamOutput&) = delete;
  StreamOutput& operator=(const StreamOutput&) = delete;
  std::FILE* stream() { return file_; }
  void commit() { close_checked(file_, path_); }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
};

/// Writes through a temporary file in the destination's directory and renames it into
/// place, so readers never see a partial file and a failed run leaves none. An existing target
/// keeps what the user set on it:
///   - one you may not write (access(W_OK): a read-only file, for a user other than root) is
///     refused before the run, and left as it is;
///   - its permission bits (and owner and group where the user may set them) pass to the new file;
///   - a file with other hard links is rewritten in place once the output is complete, so every
///     name shows the new output (a rename would give this name a new file and leave the others
///     the old one). That copy is not atomic: a reader during it sees a partial file, and if it
///     fails the complete output stays in the temporary file, which the message names.
class AtomicOutputFile {
 public:
  explicit AtomicOutputFile(const std::string& path) : path_(path), temporary_(path + ".tmp.XXXXXX") {
    if (temporary_.size() >= sizeof(g_temporary_path))
      throw std::runtime_error("--output: path too long: '" + shown(path) + "'");
    struct stat st {};
    if (lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && access(path.c_str(), W_OK) != 0)
      throw std::runtime_error("--output: cannot write '" + shown(path) + "': " + std::strerror(errno) +
                               " (it is left as it is)");
    const int fd = mkstemp(temporary_.data());
    if (fd < 0)
      throw std::runtime_error("--output: cannot create a file beside '" + shown(path) + "': " + std::strerror(errno));
    std::strcpy(g_temporary_path, temporary_.c_str());
    // mkstemp makes the file 0600; give it the permissions an ordinary new file would get.
    const mode_t mask = umask(0);
    umask(mask);
    fchmod(fd, 0666 & ~mask);
    file_ = fdopen(fd, "w");
    if (file_ == nullptr) {
      close(fd);
      discard();
      throw std::runtime_error("cannot open '" + temporary_ + "': " + std::strerror(errno));
    }
    std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  }
  ~AtomicOutputFile() {
    if (file_ != nullptr) std::fclose(file_);
    if (!committed_) discard();
  }
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  std::FILE* stream() { return file_; }

  void commit() {
    close_checked(file_, temporary_);
    // The destination may have changed kind since output_target() looked: rename only onto a
    // regular file or a free name.
    struct stat st {};
    const bool exists = lstat(path_.c_str(), &st) == 0;
    if (exists && !S_ISREG(st.st_mode))
      throw std::runtime_error("'" + shown(path_) + "' is no longer a regular file; the output is left in '" +
                               temporary_ + "'");
    if (exists && st.st_nlink > 1) {
      write_in_place();
      return;
    }
    if (exists) {
      // The file's permission bits, not the umask's; its owner and group where allowed (root).
      chmod(temporary_.c_str(), st.st_mode & 0777);
      if (chown(temporary_.c_str(), st.st_uid, st.st_gid) != 0) {
        // Not allowed to give it this owner or group: the new file is the user's, as any new file.
      }
    }
    if (std::rename(temporary_.c_str(), path_.c_str()) != 0)
      throw std::runtime_error("cannot rename '" + temporary_ + "' to '" + shown(path_) + "': " + std::strerror(errno));
    committed_ = true;
    g_temporary_path[0] = '\0';
  }

 private:
  /// Copies the complete temporary file into the target (keeping its inode, so its other hard
  /// links), then removes the temporary one; on failure keeps it and says where the output is.
  void write_in_place() {
    const int in = open(temporary_.c_str(), O_RDONLY | O_CLOEXEC);
    const int out = in < 0 ? -1 : open(path_.c_str(), O_WRONLY | O_TRUNC | O_NOCTTY | O_CLOEXEC);
    bool ok = in >= 0 && out >= 0;
    char buffer[1 << 16];
    while (ok) {
      const ssize_t n = read(in, buffer, sizeof buffer);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        ok = n == 0;
        break;
      }
      for (ssize_t done = 0; ok && done < n;) {
        const ssize_t m = write(out, buffer + done, static_cast<std::size_t>(n - done));
        if (m < 0 && errno == EINTR) continue;
        if (m <= 0) ok = false;
        else done += m;
      }
    }
    const int error = errno;
    if (out >= 0 && close(out) != 0) ok = false;
    if (in >= 0) close(in);
    if (!ok) {
      committed_ = true;  // keep the temporary file: it holds the only complete output
      g_temporary_path[0] = '\0';
      throw std::runtime_error("cannot write '" + shown(path_) + "' in place (it has other hard links): " +
                               std::strerror(error) + "; the complete output is in '" + temporary_ + "'");
    }
    committed_ = true;
    discard();
  }

  void discard() {
    unlink(temporary_.c_str());
    g_temporary_path[0] = '\0';
  }

  std::string path_;
  std::string temporary_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

/// Every signal whose default action ends the process: each removes the temporary output file
/// first (SIGKILL and SIGSTOP cannot be caught). Before, SIGUSR1, SIGALRM or SIGPIPE left it.
void remove_temporary_file_on_signals() {
  for (int signal_number : {SIGHUP, SIGINT, SIGQUIT, SIGTERM, SIGUSR1, SIGUSR2, SIGALRM, SIGPIPE, SIGVTALRM, SIGPROF,
                            SIGXCPU, SIGXFSZ, SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGTRAP, SIGSYS, SIGIO,
                            SIGPWR, SIGSTKFLT})
    std::signal(signal_number, remove_temporary_and_exit);
  for (int signal_number = SIGRTMIN; signal_number <= SIGRTMAX; ++signal_number)
    std::signal(signal_number, remove_temporary_and_exit);
}

/// Whether `a` and `b` name the same file (the same inode), e.g. --output and --config.
bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  return stat(a.c_str(), &sa) == 0 && stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

int main_with_exit_code(int argc, char** argv) {
  Options options;
  std::unique_ptr<Simulator> simulator;
  OutputTarget output;
  try {
    options = parse_options(argc, argv);
    if (options.help) {
      print_help(std::cout);
      return 0;
    }
    simulator = make_simulator(read_scene(options));
    output = output_target(options.output_path);
    if (output.kind != OutputTarget::Kind::kStdout && same_file(output.path, options.config_path))
      throw UsageError("--output: '" + shown(options.output_path) + "' is the scene file given to --config; the "
                       "output would overwrite it: give another file");
  } catch (const UsageError& e) {
    std::cerr << "simulate: error: " << e.what() << "\nTry 'simulate --help' for the options and keys.\n";
    return kExitBadInput;
  } catch (const InvalidParameter& e) {
    std::cerr << "simulate: error: " << e.what() << "\n";
    return kExitBadInput;
  }

  const SampleTimes times(options.duration, options.output_rate);
  try {
    if (output.kind == OutputTarget::Kind::kStdout) {
      run(*simulator, times, options.max_steps, stdout);
      if (std::fflush(stdout) != 0 || std::ferror(stdout))
        throw std::runtime_error(std::string("cannot write to stdout: ") + std::strerror(errno));
    } else if (output.kind == OutputTarget::Kind::kStream) {
      StreamOutput stream(output.path);
      run(*simulator, times, options.max_steps, stream.stream());
      stream.commit();
    } else {
      remove_temporary_file_on_signals();
      AtomicOutputFile file(output.path);
      run(*simulator, times, options.max_steps, file.stream());
      file.commit();
    }
  } catch (const StepBudgetExceeded& e) {
    std::cerr << "simulate: error: " << e.what() << "\n";
    return kExitStepBudget;
  } catch (const std::exception& e) {
    std::cerr << "simulate: error: " << e.what() << "\n";
    return kExitRuntimeError;
  }
  return 0;
}

}  // namespace
}  // namespace spinning_top

int main(int argc, char** argv) { return spinning_top::main_with_exit_code(argc, argv); }

// The batch simulator's command-line contract (issue 2, "Batch simulator"; doc/simulate.md),
// tested on the built executable: CSV layout and output instants, the physics of the rows it
// writes, and exit code 2 with nothing written for every kind of bad input.
#include <fcntl.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <dirent.h>
#include <thread>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "spinning_top/config.hpp"
#include "spinning_top/integrator_registry.hpp"

#ifndef SIMULATE_EXECUTABLE
#error "SIMULATE_EXECUTABLE must name the built simulate executable"
#endif
#ifndef SPINNING_TOP_SOURCE_DIR
#error "SPINNING_TOP_SOURCE_DIR must name the package's source directory"
#endif

namespace {

const std::string kHeader =
    "t,qw,qx,qy,qz,gx,gy,gz,px,py,pz,normal_force,contact_force_x,contact_force_y,energy,phase,event";
const std::string kIntegratorComment = "# integrator: ";
const std::string kFixedTipYaml = std::string(SPINNING_TOP_SOURCE_DIR) + "/config/fixed_tip.yaml";
const std::string kViscousYaml = std::string(SPINNING_TOP_SOURCE_DIR) + "/config/viscous.yaml";

// The toy top of config/fixed_tip.yaml (checked against the file in FirstRowIsTheInitialState).
constexpr double kMass = 0.1, kA = 4e-5, kC = 6e-5, kH = 0.02, kG = 9.80665, kTilt = 0.3, kSpin = 150.0;

enum Column { kT, kQw, kQx, kQy, kQz, kGx, kGy, kGz, kPx, kPy, kPz, kNormal, kFx, kFy, kEnergy, kColumns };

struct Row {
  std::vector<double> values;  ///< kColumns numbers
  std::string phase, event;    ///< the text columns after them
};

struct Result {
  int exit_code = -1;
  std::string out, err;
};

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool exists(const std::string& path) {
  struct stat info;
  return stat(path.c_str(), &info) == 0;
}

std::vector<std::string> directory_entries(const std::string& path) {
  std::vector<std::string> names;
  if (DIR* dir = opendir(path.c_str())) {
    while (const dirent* entry = readdir(dir))
      if (std::string(entry->d_name) != "." && std::string(entry->d_name) != "..") names.push_back(entry->d_name);
    closedir(dir);
  }
  return names;
}

class SimulateTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = ::testing::TempDir() + "test_simulate.XXXXXX";
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    output_dir_ = dir_ + "/out";
    ASSERT_EQ(mkdir(output_dir_.c_str(), 0755), 0);
  }
  void TearDown() override { std::system(("rm -rf '" + dir_ + "'").c_str()); }

  /// Starts simulate with these arguments (no shell), its stdout and stderr to files in dir_;
  /// as the user `uid` if it is not -1 (the test then runs as root).
  pid_t start(const std::vector<std::string>& args, uid_t uid = static_cast<uid_t>(-1)) {
    const std::string out_path = dir_ + "/stdout", err_path = dir_ + "/stderr";
    const pid_t pid = fork();
    if (pid == 0) {
      if (!freopen(out_path.c_str(), "w", stdout) || !freopen(err_path.c_str(), "w", stderr)) _exit(127);
      if (uid != static_cast<uid_t>(-1) && (setgroups(0, nullptr) != 0 || setgid(uid) != 0 || setuid(uid) != 0))
        _exit(126);
      std::vector<char*> argv{const_cast<char*>(SIMULATE_EXECUTABLE)};
      for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
      argv.push_back(nullptr);
      execv(SIMULATE_EXECUTABLE, argv.data());
      _exit(127);
    }
    return pid;
  }

  /// Runs simulate with these arguments (no shell), capturing stdout and stderr.
  Result simulate(const std::vector<std::string>& args, uid_t uid = static_cast<uid_t>(-1)) {
    const std::string out_path = dir_ + "/stdout", err_path = dir_ + "/stderr";
    const pid_t pid = start(args, uid);
    int status = 0;
    waitpid(pid, &status, 0);
    Result result;
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    result.out = read_file(out_path);
    result.err = read_file(err_path);
    return result;
  }

  std::string write_yaml(const std::string& name, const std::string& text) {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << text;
    return path;
  }

  /// Splits CSV text into its comment line (what integrator ran), the header and the rows,
  /// checking the comment's form and each row's shape.
  static std::vector<Row> parse_csv(const std::string& text, std::string* header = nullptr,
                                    std::string* integrator = nullptr) {
    std::istringstream lines(text);
    std::string line;
    std::getline(lines, line);
    EXPECT_EQ(line.rfind(kIntegratorComment, 0), 0u) << line;
    if (integrator) *integrator = line.substr(std::min(line.size(), kIntegratorComment.size()));
    std::getline(lines, line);
    if (header) *header = line;
    std::vector<Row> rows;
    while (std::getline(lines, line)) {
      std::vector<std::string> fields;
      std::size_t start = 0;
      for (std::size_t comma; (comma = line.find(',', start)) != std::string::npos; start = comma + 1)
        fields.push_back(line.substr(start, comma - start));
      fields.push_back(line.substr(start));
      EXPECT_EQ(fields.size(), static_cast<std::size_t>(kColumns + 2)) << line;
      if (fields.size() != static_cast<std::size_t>(kColumns + 2)) continue;
      Row row;
      for (int i = 0; i < kColumns; ++i) {
        char* end = nullptr;
        row.values.push_back(std::strtod(fields[i].c_str(), &end));
        EXPECT_EQ(*end, '\0') << "not a number: '" << fields[i] << "'";
      }
      row.phase = fields[kColumns];
      row.event = fields[kColumns + 1];
      EXPECT_TRUE(row.phase == "contact" || row.phase == "flight" || row.phase == "skim") << line;
      rows.push_back(row);
    }
    return rows;
  }

  std::string dir_, output_dir_;
};

TEST_F(SimulateTest, HeaderIsExactlyTheContract) {
  const Result r = simulate({"--config", kFixedTipYaml, "--duration", "0.01"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string header, integrator;
  parse_csv(r.out, &header, &integrator);
  EXPECT_EQ(header, kHeader);
  // The scene file says nothing of the integrator: auto runs the closed form.
  EXPECT_EQ(integrator.rfind("auto: exact: closed form, nutation period ", 0), 0u) << integrator;
}

TEST_F(SimulateTest, WhereExactRefusesTheStateTheCommentNamesTheFallbackAndTheReason) {
  // A top at rest without spin on a frictionless floor without gravity: nothing drives the
  // nutation, the closed form's cubic vanishes and exact refuses; auto runs dop853.
  const std::string frictionless = std::string(SPINNING_TOP_SOURCE_DIR) + "/config/frictionless.yaml";
  const Result r = simulate({"--config", frictionless, "--set", "gravity=0", "--set", "initial/spin=0"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string integrator;
  const std::vector<Row> rows = parse_csv(r.out, nullptr, &integrator);
  EXPECT_EQ(integrator.rfind("auto: dop853, tolerance 1e-12 (exact refused: ", 0), 0u) << integrator;
  EXPECT_NE(integrator.find("nothing drives the nutation"), std::string::npos) << integrator;
  // And the fallback's rows are physics: nothing acts on the top (R = m g = 0, no torque), so it
  // stays where it is, with its energy.
  ASSERT_EQ(rows.size(), 1001u);
  for (const Row& row : rows) {
    EXPECT_EQ(row.values[kGz], rows.front().values[kGz]);
    EXPECT_EQ(row.values[kEnergy], rows.front().values[kEnergy]);
    EXPECT_EQ(row.values[kPx], rows.front().values[kPx]);
  }
}

TEST_F(SimulateTest, RowsAtEveryOutputInstantFromZeroToTheEndInclusive) {
  struct Case {
    std::string duration, rate;
    std::vector<double> times;
  };
  // 0.25 s at 8 Hz is exactly 2 intervals; 0.3 s at 8 Hz is not a multiple (last row at 0.3);
  // 1.1 * 100 is 110.00000000000001 in doubles, a multiple only up to decimal round-off: 111
  // rows ending at 110 / 100 = 1.1, not a 112th row at "t = duration" a few ulps later.
  std::vector<double> to_1_1;
  for (int i = 0; i <= 110; ++i) to_1_1.push_back(i / 100.0);
  const std::vector<Case> cases = {
      {"0.25", "8", {0.0, 0.125, 0.25}},
      {"0.3", "8", {0.0, 0.125, 0.25, 0.3}},
      {"1.1", "100", to_1_1},
  };
  for (const Case& c : cases) {
    const Result r = simulate({"--config", kFixedTipYaml, "--duration", c.duration, "--output-rate", c.rate});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::vector<Row> rows = parse_csv(r.out);
    ASSERT_EQ(rows.size(), c.times.size()) << c.duration << " s at " << c.rate << " Hz";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      EXPECT_EQ(rows[i].values[kT], c.times[i]);  // %.17g round-trips a double exactly
      EXPECT_EQ(rows[i].event, "");
    }
  }
  // The defaults: 10 s at 100 Hz, t_i = i / 100 (one division each, no accumulated round-off).
  const Result r = simulate({"--config", kFixedTipYaml});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<Row> rows = parse_csv(r.out);
  ASSERT_EQ(rows.size(), 1001u);
  for (std::size_t i = 0; i < rows.size(); ++i) ASSERT_EQ(rows[i].values[kT], static_cast<double>(i) / 100.0);
}

TEST_F(SimulateTest, FileOutputEqualsStdoutAndLeavesNoTemporaryFile) {
  const std::string csv = output_dir_ + "/run.csv";
  const Result to_file = simulate({"--config", kFixedTipYaml, "--duration", "0.5", "--output", csv});
  ASSERT_EQ(to_file.exit_code, 0) << to_file.err;
  EXPECT_EQ(to_file.out, "");
  const Result to_stdout = simulate({"--config", kFixedTipYaml, "--duration", "0.5"});
  ASSERT_EQ(to_stdout.exit_code, 0) << to_stdout.err;
  EXPECT_EQ(read_file(csv), to_stdout.out);
  EXPECT_EQ(directory_entries(output_dir_), std::vector<std::string>{"run.csv"});
}

// --output never replaces what is not a regular file: renaming the temporary file onto a FIFO
// or a device node would replace the node itself (as root, `--output /dev/null` replaced the
// system's /dev/null). A FIFO and a device are written into; a directory is refused.
TEST_F(SimulateTest, AFifoAsOutputIsWrittenIntoAndStaysAFifo) {
  const std::string fifo = output_dir_ + "/rows";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // The read end, opened first without blocking: the 0.5 s run (~14 kB) fits the pipe's buffer,
  // so simulate finishes before we read, and a run that replaced the FIFO leaves it empty.
  const int read_end = open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(read_end, 0);
  const Result r = simulate({"--config", kFixedTipYaml, "--duration", "0.5", "--output", fifo});
  std::string received;
  char buffer[4096];
  for (ssize_t n; (n = read(read_end, buffer, sizeof buffer)) > 0;) received.append(buffer, static_cast<std::size_t>(n));
  close(read_end);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Result to_stdout = simulate({"--config", kFixedTipYaml, "--duration", "0.5"});
  EXPECT_EQ(received, to_stdout.out);
  struct stat st {};
  ASSERT_EQ(lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced";
  EXPECT_EQ(directory_entries(output_dir_), std::vector<std::string>{"rows"});  // no temporary left
}

TEST_F(SimulateTest, ALinkToACharacterDeviceIsWrittenThroughAndNeitherIsReplaced) {
  // A scratch device-like path: a link to /dev/null in the test's directory. Were the device
  // replaced, the rename would land on the link, never on /dev/null itself.
  const std::string device = output_dir_ + "/null";
  ASSERT_EQ(symlink("/dev/null", device.c_str()), 0);
  const Result r = simulate({"--config", kFixedTipYaml, "--duration", "0.5", "--output", device});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "");
  struct stat st {};
  ASSERT_EQ(lstat(device.c_str(), &st), 0);
  EXPECT_TRUE(S_ISLNK(st.st_mode)) << "the link was replaced";
  ASSERT_EQ(stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  EXPECT_EQ(directory_entries(output_dir_), std::vector<std::string>{"null"});
}

TEST_F(SimulateTest, ALinkToARegularFileReplacesTheFileAndKeepsTheLink) {
  const std::string file = dir_ + "/target.csv", link = output_dir_ + "/latest.csv";
  std::ofstream(file) << "previous run\n";
  ASSERT_EQ(symlink(file.c_str(), link.c_str()), 0);
  const Result r = simulate({"--config", kFixedTipYaml, "--duration", "0.5", "--output", link});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  struct stat st {};
  ASSERT_EQ(lstat(link.c_str(), &st), 0);
  EXPECT_TRUE(S_ISLNK(st.st_mode)) << "the link was replaced by a file";
  EXPECT_EQ(read_file(file), simulate({"--config", kFixedTipYaml, "--duration", "0.5"}).out);
}

// Issue 19, item 12: every signal that ends the run removes the temporary file. Before, only
// SIGINT, SIGTERM and SIGHUP did: SIGUSR1, SIGALRM and SIGPIPE left run.csv.tmp.XXXXXX behind.
TEST_F(SimulateTest, ASignalThatEndsTheRunLeavesNoTemporaryFile) {
  const std::string csv = output_dir_ + "/run.csv";
  for (const int signal_number : {SIGUSR1, SIGALRM, SIGPIPE, SIGUSR2, SIGTERM}) {
    // rk4 at 1e-6 s for 1e4 s: far longer than the test waits.
    const pid_t pid = start({"--config", kFixedTipYaml, "--set", "integrator=rk4", "--set", "step=1e-6",
                             "--duration", "1e4", "--output-rate", "0.01", "--output", csv});
    // Wait until the temporary file exists (a guard of 30 s, not a measure).
    for (int i = 0; i < 3000 && directory_entries(output_dir_).empty(); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    ASSERT_EQ(directory_entries(output_dir_).size(), 1u) << "no temporary file appeared";
    kill(pid, signal_number);
    int status = 0;
    waitpid(pid, &status, 0);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal_number) << "signal " << signal_number;
    for (const std::string& left : directory_entries(output_dir_)) {
      ADD_FAILURE() << "signal " << signal_number << " left " << left;
      unlink((output_dir_ + "/" + left).c_str());  // judge the next signal alone
    }
  }
}

// Issue 19, item 12: a file the user may not write is not replaced (before, the rename replaced
// it whenever the directory was writable). Root may write any file, so as root the run is made as
// the user nobody (uid 65534) on a root-owned read-only file.
TEST_F(SimulateTest, AReadOnlyOutputIsLeftAsItIs) {
  const bool root = geteuid() == 0;
  const uid_t user = root ? 65534 : static_cast<uid_t>(-1);
  ASSERT_EQ(chmod(dir_.c_str(), 0755), 0);
  ASSERT_EQ(chmod(output_dir_.c_str(), 0777), 0);  // writable: the rename would succeed
  const std::string scene = write_yaml("scene.yaml", read_file(kFixedTipYaml));
  ASSERT_EQ(chmod(scene.c_str(), 0644), 0);
  const std::string csv = output_dir_ + "/run.csv";
  std::ofstream(csv) << "keep\n";
  ASSERT_EQ(chmod(csv.c_str(), 0444), 0);
  const Result r = simulate({"--config", scene, "--duration", "0.1", "--output", csv}, user);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("cannot write '" + csv + "'"), std::string::npos) << r.err;
  EXPECT_EQ(read_file(csv), "keep\n");
  EXPECT_EQ(directory_entries(output_dir_), std::vector<std::string>{"run.csv"});
}

// Issue 19, item 12: --output naming the scene file (the same path, a hard link or a symbolic
// link to it) is refused before anything is written; before, the CSV replaced the scene file.
TEST_F(SimulateTest, AnOutputThatIsTheSceneFileIsRefused) {
  const std::string text = read_file(kFixedTipYaml);
  const std::string scene = write_yaml("scene.yaml", text);
  const std::string hard = output_dir_ + "/hard.yaml", soft = output_dir_ + "/soft.yaml";
  ASSERT_EQ(link(scene.c_str(), hard.c_str()), 0);
  ASSERT_EQ(symlink(scene.c_str(), soft.c_str()), 0);
  for (const std::string& output : {scene, hard, soft}) {
    const Result r = simulate({"--config", scene, "--duration", "0.1", "--output", output});
    EXPECT_EQ(r.exit_code, 2) << output << ": " << r.err;
    EXPECT_NE(r.err.find("is the scene file given to --config"), std::string::npos) << r.err;
    EXPECT_EQ(read_file(scene), text) << output;
  }
}

// Issue 19, item 12: an existing output keeps its permission bits and its hard links (a file
// with other links is rewritten in place once the output is complete). Before, the rename gave
// it a new inode with mode 0644 (the umask's): run.csv lost its 0640 and other.csv kept the old
// rows.
TEST_F(SimulateTest, AnExistingOutputKeepsItsModeAndItsHardLinks) {
  const std::string csv = output_dir_ + "/run.csv", other = output_dir_ + "/other.csv";
  const std::string expected = simulate({"--config", kFixedTipYaml, "--duration", "0.1"}).out;
  std::ofstream(csv) << "previous run\n";
  ASSERT_EQ(chmod(csv.c_str(), 0640), 0);
  Result r = simulate({"--config", kFixedTipYaml, "--duration", "0.1", "--output", csv});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  struct stat st {};
  ASSERT_EQ(stat(csv.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
  EXPECT_EQ(read_file(csv), expected);
  ASSERT_EQ(link(csv.c_str(), other.c_str()), 0);
  std::ofstream(csv) << "previous run\n";
  r = simulate({"--config", kFixedTipYaml, "--duration", "0.1", "--output", csv});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_file(other), expected) << "the hard link was broken";
  struct stat other_st {};
  ASSERT_EQ(stat(csv.c_str(), &st), 0);
  ASSERT_EQ(stat(other.c_str(), &other_st), 0);
  EXPECT_EQ(st.st_ino, other_st.st_ino);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
  EXPECT_EQ(directory_entries(output_dir_).size(), 2u);  // no temporary file left
}

TEST_F(SimulateTest, ADirectoryAsOutputIsRefusedWithCode2AndADashIsStdout) {
  const Result r = simulate({"--config", kFixedTipYaml, "--duration", "0.1", "--output", output_dir_});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("--output"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("directory"), std::string::npos) << r.err;
  EXPECT_TRUE(directory_entries(output_dir_).empty());
  const Result dash = simulate({"--config", kFixedTipYaml, "--duration", "0.1", "--output", "-"});
  ASSERT_EQ(dash.exit_code, 0) << dash.err;
  EXPECT_EQ(dash.out, simulate({"--config", kFixedTipYaml, "--duration", "0.1"}).out);
  EXPECT_FALSE(exists("-"));
}

// Determinism (doc/simulate.md): the same inputs on the same build give the same bytes, and the
// default's rows do not depend on the output rate either (exact answers each instant in closed
// form, dop853 and radau9 by dense output, so requests never move their steps): the rows at the
// instants two rates share are equal to the bit.
TEST_F(SimulateTest, TheDefaultsRowsAreBitIdenticalAcrossRunsAndOutputRates) {
  for (const char* scene : {"fixed_tip", "frictionless", "viscous"}) {
    const std::string file = std::string(SPINNING_TOP_SOURCE_DIR) + "/config/" + scene + ".yaml";
    for (const char* friction : {"", "friction=1e5"}) {
      if (*friction != '\0' && std::string(scene) != "viscous") continue;
      std::vector<std::string> args = {"--config", file, "--duration", "2"};
      if (*friction != '\0') args.insert(args.end(), {"--set", friction});
      const Result first = simulate(args), again = simulate(args);
      ASSERT_EQ(first.exit_code, 0) << first.err;
      EXPECT_EQ(first.out, again.out) << scene << " " << friction << ": two runs differ";
      std::vector<std::string> fine_args = args;
      fine_args.insert(fine_args.end(), {"--output-rate", "1000"});
      const Result fine = simulate(fine_args);
      ASSERT_EQ(fine.exit_code, 0) << fine.err;
      // Rows are t = i / rate: every 10th row at 1 kHz is a row at 100 Hz, compared as text.
      std::vector<std::string> coarse_rows, fine_rows;
      std::istringstream a(first.out), b(fine.out);
      for (std::string line; std::getline(a, line);) coarse_rows.push_back(line);
      for (std::string line; std::getline(b, line);) fine_rows.push_back(line);
      ASSERT_EQ(coarse_rows.size(), 203u);  // comment, header, 201 rows
      ASSERT_EQ(fine_rows.size(), 2003u);
      EXPECT_EQ(coarse_rows[0], fine_rows[0]);  // the same method
      for (std::size_t i = 2; i < coarse_rows.size(); ++i)
        EXPECT_EQ(coarse_rows[i], fine_rows[2 + 10 * (i - 2)]) << scene << " " << friction << ", row " << i;
    }
  }
}

TEST_F(SimulateTest, FixedTipSceneFileConservesEnergyOverTenSeconds) {
  const Result r = simulate({"--config", kFixedTipYaml, "--duration", "10"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<Row> rows = parse_csv(r.out);
  ASSERT_EQ(rows.size(), 1001u);
  // auto runs exact here, whose energy is round-off (measured 1.6e-16 relative); 1e-9 (the
  // issue's bound) flags a wrong energy formula or a broken integrator, not round-off.
  const double e0 = rows.front().values[kEnergy];
  double worst = 0.0;
  for (const Row& row : rows) worst = std::max(worst, std::abs(row.values[kEnergy] - e0) / e0);
  EXPECT_LT(worst, 1e-9);
  EXPECT_EQ(rows.back().event, "");
}

TEST_F(SimulateTest, FirstRowIsTheInitialStateFromTheEulerAngles) {
  const double heading = 0.7, spin_angle = 0.4, precession = 2.0, nutation = 1.0;
  const Result r = simulate({"--config", kFixedTipYaml, "--duration", "0.01", "--set", "initial/heading=0.7",
                             "--set", "initial/spin_angle=0.4", "--set", "initial/precession_rate=2", "--set",
                             "initial/nutation_rate=1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<Row> rows = parse_csv(r.out);
  ASSERT_FALSE(rows.empty());
  const std::vector<double>& v = rows.front().values;
  EXPECT_EQ(v[kT], 0.0);
  // q0 = qz(phi) qx(theta) qz(psi), multiplied out by hand (PHYSICS.md, initial state).
  const double ct = std::cos(kTilt / 2), st = std::sin(kTilt / 2);
  const double sum = (heading + spin_angle) / 2, difference = (heading - spin_angle) / 2;
  const double q[4] = {ct * std::cos(sum), st * std::cos(difference), st * std::sin(difference), ct * std::sin(sum)};
  const double sign = (v[kQw] * q[0] + v[kQx] * q[1] + v[kQy] * q[2] + v[kQz] * q[3]) < 0 ? -1.0 : 1.0;  // q ~ -q
  // A few ulps of a unit quantity: the core builds q from the same angles by another route.
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(sign * v[kQw + i], q[i], 1e-15) << "component " << i;
  // G = h e_Z, e_Z = (sin(theta) sin(phi), -sin(theta) cos(phi), cos(theta)); the tip at the origin.
  EXPECT_NEAR(v[kGx], kH * std::sin(kTilt) * std::sin(heading), 1e-15 * kH);
  EXPECT_NEAR(v[kGy], -kH * std::sin(kTilt) * std::cos(heading), 1e-15 * kH);
  EXPECT_NEAR(v[kGz], kH * std::cos(kTilt), 1e-15 * kH);
  EXPECT_EQ(v[kPx], 0.0);
  EXPECT_EQ(v[kPy], 0.0);
  // E = 1/2 A0 |omega_perp|^2 + 1/2 C omega_Z^2 + m g h cos(theta) for the fixed tip
  // (v_G = h omega x e_Z adds 1/2 m h^2 |omega_perp|^2), |omega_perp|^2 = phidot^2 sin^2 + thetadot^2.
  const double omega_perp2 = precession * precession * std::sin(kTilt) * std::sin(kTilt) + nutation * nutation;
  const double energy = 0.5 * (kA + kMass * kH * kH) * omega_perp2 + 0.5 * kC * kSpin * kSpin +
                        kMass * kG * kH * std::cos(kTilt);
  EXPECT_NEAR(v[kEnergy], energy, 1e-14 * energy);
  EXPECT_EQ(rows.front().event, "");
}

// t_fall = integral from theta0 to pi/2 of dtheta / sqrt(2 m g h (cos theta0 - cos theta) / A0):
// without spin the fixed-tip top is a physical pendulum about its tip. theta = theta0 + w^2
// removes the inverse-square-root singularity at theta0; Simpson's rule on the smooth rest.
double pendulum_fall_time() {
  const double k = 2.0 * kMass * kG * kH / (kA + kMass * kH * kH);
  auto integrand = [&](double w) {
    if (w == 0.0) return 2.0 / std::sqrt(k * std::sin(kTilt));
    // cos(theta0) - cos(theta0 + s) = 2 sin(theta0 + s/2) sin(s/2), free of cancellation.
    const double s = w * w;
    return 2.0 * w / std::sqrt(k * 2.0 * std::sin(kTilt + s / 2) * std::sin(s / 2));
  };
  const int n = 2000;  // even; 200 and 20000 points agree to 5e-13 s
  const double upper = std::sqrt(M_PI / 2 - kTilt), step = upper / n;
  double sum = integrand(0.0) + integrand(upper);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * integrand(i * step);
  return sum * step / 3.0;
}

TEST_F(SimulateTest, TopWithoutSpinFallsAndTheLastRowSaysSo) {
  // The needle (no rim): the scene file's rim would touch the floor at 0.857 rad, before the axis.
  const Result r = simulate({"--config", kFixedTipYaml, "--set", "initial/spin=0", "--set", "rim_radius=0", "--set",
                             "rim_distance=0", "--duration", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.err;  // an event ends the run early, still a success
  const std::vector<Row> rows = parse_csv(r.out);
  ASSERT_GE(rows.size(), 2u);
  for (std::size_t i = 0; i + 1 < rows.size(); ++i) {
    EXPECT_EQ(rows[i].event, "");
    EXPECT_EQ(rows[i].values[kT], static_cast<double>(i) / 100.0);
  }
  const Row& last = rows.back();
  EXPECT_EQ(last.event, "fallen");
  // The event is located within the step (to ~1e-14 s), where the axis reaches the floor: z_G
  // = h e_Zz = 0 up to |dz_G/dt| (< 1 m/s here) times that.
  EXPECT_NEAR(last.values[kGz], 0.0, 1e-12);
  EXPECT_GT(last.values[kT], rows[rows.size() - 2].values[kT]);
  // Its time is the pendulum's fall time (0.153635789578779 s). Measured difference 1.5e-11 s
  // at the default tolerance 1e-10; 1e-9 s leaves room for the error that the state's
  // local tolerance allows, and still catches an event reported at the end of a step.
  EXPECT_NEAR(last.values[kT], pendulum_fall_time(), 1e-9);
  // Energy is conserved through the fall (as in FixedTipSceneFileConservesEnergyOverTenSeconds).
  EXPECT_NEAR(last.values[kEnergy], rows.front().values[kEnergy], 1e-9 * rows.front().values[kEnergy]);
}

TEST_F(SimulateTest, FastNutationLiftsTheTipWhereTheNormalForceVanishes) {
  // theta_dot0 = 20 rad/s: the centripetal term m h cos(theta) theta_dot^2 = 0.76 N is close to
  // m g = 0.98 N, and the nutation drives R through zero within 0.05 s.
  // after_lift_off: stop, the contact model's end (flying on is HybridRun's, test_hybrid.cpp).
  const Result r = simulate({"--config", kFixedTipYaml, "--set", "initial/nutation_rate=20", "--set",
                             "after_lift_off=stop", "--duration", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<Row> rows = parse_csv(r.out);
  ASSERT_GE(rows.size(), 2u);
  EXPECT_EQ(rows.back().event, "lift_off");
  EXPECT_LT(rows.back().values[kT], 1.0);
  // Located to ~1e-14 s with |dR/dt| of order m g times the nutation rate (~20 N/s): R = 0
  // to far better than 1e-10 N (measured 4e-17 N); every earlier row has R > 0.
  EXPECT_NEAR(rows.back().values[kNormal], 0.0, 1e-10);
  for (std::size_t i = 0; i + 1 < rows.size(); ++i) EXPECT_GT(rows[i].values[kNormal], 0.0);

  // theta_dot0 = 100 rad/s: m h cos(theta) theta_dot^2 = 19 N >> m g, so R < 0 already at t = 0:
  // the run is one row, the initial state, with the event, and the floor force shown is 0: the
  // floor cannot pull (issue 19, item 9: it showed the invalid state's negative R).
  const Result at_start =
      simulate({"--config", kFixedTipYaml, "--set", "initial/nutation_rate=100", "--set", "after_lift_off=stop",
                "--duration", "1"});
  ASSERT_EQ(at_start.exit_code, 0) << at_start.err;
  const std::vector<Row> one = parse_csv(at_start.out);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].values[kT], 0.0);
  EXPECT_EQ(one[0].values[kNormal], 0.0);
  EXPECT_EQ(one[0].event, "lift_off");
}

TEST_F(SimulateTest, BadInputExitsWithCode2NamesTheCulpritAndWritesNothing) {
  const std::string scene = read_file(kFixedTipYaml);
  const std::string unknown_key = write_yaml("unknown.yaml", scene + "colour: red\n");
  const std::string nested_unknown = write_yaml("nested.yaml", scene + "  wobble: 1.0\n");  // under initial:
  std::string without_mass_text;
  {
    std::istringstream lines(scene);
    for (std::string line; std::getline(lines, line);)
      if (line.rfind("mass:", 0) != 0) without_mass_text += line + "\n";
  }
  const std::string without_mass = write_yaml("without_mass.yaml", without_mass_text);
  const std::string malformed = write_yaml("malformed.yaml", "scene: fixed_tip\nmass: [0.1\n");
  const std::string twice = write_yaml("twice.yaml", scene + "mass: 0.2\n");
  const std::string no_value = write_yaml("no_value.yaml", scene + "tolerance:\n");
  const std::string not_a_number = write_yaml("nan.yaml", scene + "step: fast\n");
  // A second document would be ignored without a word: its "mass: -1" never checked.
  const std::string two_documents = write_yaml("two_documents.yaml", scene + "---\nmass: -1\n");
  const std::string quoted = write_yaml("quoted.yaml", scene + "gravity: \"9.8\"\n");
  const std::string tagged = write_yaml("tagged.yaml", without_mass_text + "mass: !!str 0.1\n");
  const std::string octal = write_yaml("octal.yaml", scene + "gravity: 010\n");
  const std::string aliased = write_yaml("aliased.yaml", scene + "gravity: &g 9.8\nfriction: *g\n");

  struct Case {
    std::vector<std::string> args;
    std::string named;  ///< must appear in the message on stderr
  };
  const std::vector<Case> cases = {
      {{"--config", unknown_key}, "colour"},
      {{"--config", nested_unknown}, "initial/wobble"},
      {{"--config", kFixedTipYaml, "--set", "initial/tlt=0.3"}, "initial/tlt"},
      {{"--config", without_mass}, "mass"},
      {{"--config", kFixedTipYaml, "--set", "mass=-1"}, "mass"},
      {{"--config", kFixedTipYaml, "--set", "inertia_axial=9e-5"}, "inertia_axial"},  // C > 2A
      {{"--config", kFixedTipYaml, "--set", "initial/tilt=2"}, "initial/tilt"},     // axis below the floor
      {{"--config", kFixedTipYaml, "--set", "friction=0.1"}, "friction"},           // not the viscous scene
      {{"--config", kFixedTipYaml, "--set", "scene=ice"}, "scene"},
      {{"--config", kFixedTipYaml, "--set", "integrator=euler"}, "integrator"},
      {{"--config", not_a_number}, "step"},
      {{"--config", no_value}, "tolerance"},
      {{"--config", twice}, "mass"},
      {{"--config", malformed}, "malformed.yaml"},
      {{"--config", dir_ + "/missing.yaml"}, "missing.yaml"},
      {{"--config", two_documents}, "2 YAML documents"},
      {{"--config", output_dir_}, "is a directory"},                                     // not "scene missing"
      {{"--config", kFixedTipYaml, "--set", "mas=0.1"}, "did you mean mass?"},
      {{"--config", kFixedTipYaml, "--set", "initial/spin=1e22"}, "initial/spin"},   // was garbage, exit 0
      {{"--config", kFixedTipYaml, "--set", "initial/spin=1.4e154"}, "initial/spin"},  // was SIGABRT
      {{"--config", kFixedTipYaml, "--set", "integrator=rk4", "--set", "step=1e-300"}, "step"},
      {{"--config", kFixedTipYaml, "--set", "initial/tilt=6.5831853"}, "initial/tilt"},  // 2 pi + 0.3
      {{}, "--config"},
      {{"--config", kFixedTipYaml, "--duration", "0"}, "--duration"},
      {{"--config", kFixedTipYaml, "--duration", "-1"}, "--duration"},
      {{"--config", kFixedTipYaml, "--duration", "nan"}, "--duration"},
      {{"--config", kFixedTipYaml, "--duration", "inf"}, "--duration"},
      {{"--config", kFixedTipYaml, "--duration", "ten"}, "--duration"},
      {{"--config", kFixedTipYaml, "--output-rate", "0"}, "--output-rate"},
      {{"--config", kFixedTipYaml, "--output-rate", "-100"}, "--output-rate"},
      {{"--config", kFixedTipYaml, "--output-rate"}, "--output-rate"},
      {{"--config", kFixedTipYaml, "--set", "mass"}, "--set"},
      {{"--config", kFixedTipYaml, "--speed", "2"}, "--speed"},
      {{"--config", kFixedTipYaml, "stray"}, "stray"},
      // Issue 19, through this front end (test_scene_file and test_validation test the core):
      // /dev/zero ended in std::bad_alloc (exit 134); the others ran (exit 0), 010 with g = 10
      // where the node's rosparam gives 8, velocity_x = 1e300 with E = inf.
      {{"--config", "/dev/zero"}, "--config: '/dev/zero' is a character device"},
      {{"--config", quoted}, "gravity: '9.8' is quoted"},
      {{"--config", tagged}, "mass: has the tag !!str"},
      {{"--config", octal}, "gravity: '010' has a leading zero"},
      {{"--config", aliased}, "anchor"},
      {{"--config", kViscousYaml, "--set", "initial/velocity_x=1e300"}, "initial/velocity_x"},
      {{"--config", kFixedTipYaml, "--set", "mass=" + std::string(100000, '9') + "x"}, "(100001 characters)"},
      // exact ran to NaN rows at t = 1e20 s, exit 0 (found by the attack harness).
      {{"--config", kFixedTipYaml, "--duration", "1e20", "--output-rate", "1e-20"}, "--duration: must be at most 1e9 s"},
  };
  const std::string csv = output_dir_ + "/run.csv";
  for (const Case& c : cases) {
    std::vector<std::string> args = c.args;
    args.insert(args.end(), {"--output", csv});
    const Result r = simulate(args);
    std::string shown;
    for (const std::string& a : c.args) shown += a + " ";
    EXPECT_EQ(r.exit_code, 2) << shown << "\n" << r.err;
    EXPECT_NE(r.err.find(c.named), std::string::npos) << shown << ": message does not name '" << c.named
                                                        << "': " << r.err;
    EXPECT_EQ(r.out, "") << shown;
    EXPECT_TRUE(directory_entries(output_dir_).empty()) << shown << ": something was written";
    EXPECT_LT(r.err.size(), 1000u) << shown.substr(0, 200) << ": a long message";
  }
  // Nothing on stdout either when the output would have gone there, and an existing output
  // file is left as it was.
  const Result to_stdout = simulate({"--config", kFixedTipYaml, "--set", "mass=0"});
  EXPECT_EQ(to_stdout.exit_code, 2);
  EXPECT_EQ(to_stdout.out, "");
  std::ofstream(csv) << "previous run\n";
  const Result over_existing = simulate({"--config", kFixedTipYaml, "--set", "mass=0", "--output", csv});
  EXPECT_EQ(over_existing.exit_code, 2);
  EXPECT_EQ(read_file(csv), "previous run\n");
}

TEST_F(SimulateTest, UnwritableOutputIsARuntimeErrorWithCode1) {
  const std::string csv = dir_ + "/no_such_directory/run.csv";
  const Result r = simulate({"--config", kFixedTipYaml, "--duration", "0.1", "--output", csv});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(csv), std::string::npos) << r.err;
  EXPECT_FALSE(exists(csv));
}

// A run that needs more integration steps than --max-steps stops with exit code 3 and says
// so, instead of computing for hours (rk4 at step 1e-9 s over 1000 s: 1e12 substeps). The rows
// up to there stream to stdout; a file output is not created. Within the budget, the rows are
// those of a run without one.
TEST_F(SimulateTest, ARunBeyondMaxStepsStopsWithCode3) {
  const std::vector<std::string> tiny_step = {"--config", kFixedTipYaml, "--set", "integrator=rk4",
                                              "--set", "step=1e-7", "--output-rate", "100"};
  auto with = [&](std::vector<std::string> more) {
    std::vector<std::string> args = tiny_step;
    args.insert(args.end(), more.begin(), more.end());
    return args;
  };
  const Result r = simulate(with({"--duration", "1000", "--max-steps", "200000"}));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("--max-steps 200000"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("rk4, step 1e-07 s"), std::string::npos) << r.err;
  const std::vector<Row> rows = parse_csv(r.out);
  ASSERT_EQ(rows.size(), 3u);  // 200000 substeps of 1e-7 s: t = 0, 0.01, 0.02 s
  const Result full = simulate(with({"--duration", "0.02"}));
  ASSERT_EQ(full.exit_code, 0) << full.err;
  EXPECT_EQ(r.out, full.out);
  const std::string csv = output_dir_ + "/run.csv";
  const Result to_file = simulate(with({"--duration", "1000", "--max-steps", "1000", "--output", csv}));
  EXPECT_EQ(to_file.exit_code, 3) << to_file.err;
  EXPECT_TRUE(directory_entries(output_dir_).empty());
  for (const std::string bad : {"0", "1.5", "-3", "nan", "1e16"}) {
    const Result refused = simulate(with({"--max-steps", bad}));
    EXPECT_EQ(refused.exit_code, 2) << bad;
    EXPECT_NE(refused.err.find("--max-steps"), std::string::npos) << refused.err;
  }
}

// The CSV's columns are one list: the header that --help shows is the one a run writes, and
// --help describes each of its columns on a line of its own.
TEST_F(SimulateTest, HelpDescribesEveryColumnOfTheHeaderItWrites) {
  const Result help = simulate({"--help"});
  ASSERT_EQ(help.exit_code, 0) << help.err;
  const Result run = simulate({"--config", kFixedTipYaml, "--duration", "0.01"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::istringstream run_lines(run.out);
  std::string comment, header;
  std::getline(run_lines, comment);
  std::getline(run_lines, header);
  EXPECT_EQ(header, kHeader);
  const std::size_t shown = help.out.find("then the CSV header\n  " + header + "\n");
  ASSERT_NE(shown, std::string::npos) << help.out;
  std::istringstream names(header);
  for (std::string name; std::getline(names, name, ',');)
    EXPECT_NE(help.out.find("\n  " + name + " ", shown + 20 + header.size()), std::string::npos)
        << "--help does not describe the column " << name;
}

TEST_F(SimulateTest, HelpDocumentsEveryKeyWithUnitDefaultAndRequirement) {
  const Result r = simulate({"--help"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The key table: a header line "  key  unit  default  required  description", then one
  // line per key with its fields at the header's column offsets (units contain spaces).
  std::istringstream lines(r.out);
  std::vector<std::string> table;
  for (std::string line; std::getline(lines, line);) table.push_back(line);
  std::size_t header = 0;
  while (header < table.size() && table[header].rfind("  key ", 0) != 0) ++header;
  ASSERT_LT(header, table.size()) << "no key table in --help";
  const std::string& columns = table[header];
  const std::size_t unit_at = columns.find("unit"), default_at = columns.find("default"),
                    required_at = columns.find("required"), description_at = columns.find("description");
  auto field = [](const std::string& line, std::size_t from, std::size_t to) {
    std::string text = line.substr(from, to - from);
    return text.substr(0, text.find_last_not_of(' ') + 1);
  };
  for (const spinning_top::ParameterSpec& spec : spinning_top::parameter_specs()) {
    bool found = false;
    for (std::size_t i = header + 1; i < table.size() && !found; ++i) {
      const std::string& line = table[i];
      if (line.size() <= description_at || field(line, 2, unit_at) != spec.key) continue;
      found = true;
      EXPECT_EQ(field(line, unit_at, default_at), *spec.unit ? spec.unit : "-") << line;
      EXPECT_EQ(field(line, default_at, required_at), spec.default_value) << line;
      EXPECT_EQ(field(line, required_at, description_at), spec.required_in_file ? "yes" : "no") << line;
      EXPECT_EQ(line.substr(description_at), spec.description) << line;
    }
    EXPECT_TRUE(found) << "--help does not list " << spec.key;
  }
  for (const char* option : {"--config", "--set", "--duration", "--output-rate", "--output"})
    EXPECT_NE(r.out.find(option), std::string::npos) << option;
  // The integrator table: one line per registry row, with its scenes, kind and help.
  for (const spinning_top::IntegratorInfo& row : spinning_top::integrator_registry()) {
    bool found = false;
    for (const std::string& line : table) {
      if (line.rfind("  " + std::string(row.name) + " ", 0) != 0 || line.find(row.help) == std::string::npos) continue;
      found = true;
      EXPECT_NE(line.find(row.scene_names()), std::string::npos) << line;
      EXPECT_NE(line.find(spinning_top::to_string(row.kind)), std::string::npos) << line;
    }
    EXPECT_TRUE(found) << "--help does not list the integrator " << row.name;
  }
  EXPECT_NE(r.out.find(spinning_top::auto_rule_summary()), std::string::npos);  // auto's row
}

}  // namespace

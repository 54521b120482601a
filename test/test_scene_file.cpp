// The scene-file reader (issue 19, items 2, 3, 7, 8): read_scene_file is what simulate, the
// node's ~spawn, the Python module and the sweep read a scene file with, so each refusal here
// holds for every front end. A file is bounded before and while it is parsed (a regular file of
// at most 1 MiB, no anchors or aliases, at most 10,000 nodes and 16 levels), a number is a plain
// scalar that YAML 1.1 (rosparam: the node's launch file) and YAML 1.2 (yaml-cpp) read as the
// same number, and a tag or quotes never turn text into a number.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "spinning_top/scene_file.hpp"

#ifndef SPINNING_TOP_SOURCE_DIR
#error "SPINNING_TOP_SOURCE_DIR must name the package's source directory"
#endif

namespace spinning_top {
namespace {

const std::string kScene =
    "scene: fixed_tip\nmass: 0.1\ninertia_transverse: 4.0e-5\ninertia_axial: 6.0e-5\ntip_distance: 0.02\n"
    "initial:\n  tilt: 0.3\n  spin: 150.0\n";

class SceneFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = ::testing::TempDir() + "test_scene_file.XXXXXX";
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { std::system(("rm -rf '" + dir_ + "'").c_str()); }

  std::string write(const std::string& text, const std::string& name = "scene.yaml") {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }

  /// The SceneFileError's message for this file's text ("" if it was read).
  std::string refusal(const std::string& text) {
    try {
      read_scene_file(write(text));
    } catch (const SceneFileError& e) {
      return e.what();
    }
    return "";
  }

  std::string dir_;
};

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// Runs `check` in a child process and returns its exit code, or -1 if it did not finish within
/// 30 s (then it is killed): so that a reader that blocks or loops fails the test instead of
/// hanging it. The 30 s are a guard, not a measure.
int in_child(const std::function<int()>& check) {
  const pid_t child = fork();
  if (child == 0) _exit(check());
  int status = 0;
  for (int i = 0; i < 300 && waitpid(child, &status, WNOHANG) == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  if (waitpid(child, &status, WNOHANG) == 0) {
    kill(child, SIGKILL);
    waitpid(child, &status, 0);
    return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// 0 if reading `path` is refused with a message containing `expected`; 2 other message, 3 read.
int refused_with(const std::string& path, const std::string& expected) {
  try {
    read_scene_file(path);
  } catch (const SceneFileError& e) {
    return contains(e.what(), expected) ? 0 : 2;
  }
  return 3;
}

// Item 2: a file of nested maps of aliases. yaml-cpp shares an aliased node, so the file is 700
// bytes but its traversal visits 9^6 = 531,441 maps (at 9^8 the old reader took 3.6 GB and
// ended in std::bad_alloc); the old reader returned them all as keys. Refused at the first
// anchor now, before anything expands.
TEST_F(SceneFileTest, AnchorsAndAliasesAreRefusedBeforeAnythingExpands) {
  std::string bomb = "m0: &m0 {a: 1, b: 1, c: 1, d: 1, e: 1, f: 1, g: 1, h: 1, i: 1}\n";
  for (int i = 1; i <= 6; ++i) {
    bomb += "m" + std::to_string(i) + ": &m" + std::to_string(i) + " {";
    for (char k = 'a'; k <= 'i'; ++k) bomb += std::string(k == 'a' ? "" : ", ") + k + ": *m" + std::to_string(i - 1);
    bomb += "}\n";
  }
  const std::string message = refusal(bomb);
  EXPECT_TRUE(contains(message, "anchor")) << message;
  // An alias alone (its anchor elsewhere is refused first), and a merge key.
  // Named by the key whose value it is.
  EXPECT_TRUE(contains(refusal(kScene + "gravity: &g 9.8\nfriction: *g\n"), "gravity: an anchor (&g)"));
  EXPECT_TRUE(contains(refusal("scene: fixed_tip\ninitial: {spin_angle: &a !!str 1}\n"), "initial/spin_angle: an anchor (&a)"));
  EXPECT_TRUE(contains(refusal("base: {mass: 0.1}\n<<: {mass: 0.2}\n"), "merge key"));
}

// Item 2 without aliases: the node count and the depth are bounded too (a scene file has ~25
// keys, 2 levels). The old reader took both.
TEST_F(SceneFileTest, NodeCountAndDepthAreBounded) {
  std::string deep = "a:\n";
  for (int level = 1; level <= 17; ++level) deep += std::string(2 * level, ' ') + "a" + std::to_string(level) + ":\n";
  deep += std::string(36, ' ') + "x: 1\n";
  const std::string too_deep = refusal(deep);
  EXPECT_TRUE(contains(too_deep, "nested more than 16")) << too_deep;
  std::string wide;
  for (int i = 0; i < 6000; ++i) wide += "k" + std::to_string(i) + ": 1\n";  // 12,000 nodes
  const std::string too_wide = refusal(wide);
  EXPECT_TRUE(contains(too_wide, "more than 10000 YAML nodes")) << too_wide;
}

// Item 3: only a regular file of at most 1 MiB is read. /dev/zero ended in std::bad_alloc
// (simulate: exit 134), /dev/urandom grew to 2 GB, a FIFO without a writer blocked for ever
// (the node's ~spawn froze), and a 2 MB file was read whole.
TEST_F(SceneFileTest, DevicesFifosAndLargeFilesAreRefusedNamingTheFile) {
  for (const std::string device : {"/dev/zero", "/dev/urandom", "/dev/null"}) {
    try {
      read_scene_file(device);
      ADD_FAILURE() << device << " read";
    } catch (const SceneFileError& e) {
      EXPECT_TRUE(contains(e.what(), "'" + device + "' is a character device")) << e.what();
    }
  }
  const std::string large = write(std::string((1 << 20) + 1, '#'), "large.yaml");  // a comment
  try {
    read_scene_file(large);
    ADD_FAILURE() << "a file over 1 MiB was read";
  } catch (const SceneFileError& e) {
    EXPECT_TRUE(contains(e.what(), "large.yaml' is larger than 1 MiB")) << e.what();
  }
  EXPECT_NO_THROW(read_scene_file(write(kScene + std::string((1 << 20) - kScene.size(), '#'), "limit.yaml")));
  // The refusal says where the limit falls (the attack's 30 MB value, 3000 nested maps and 1 MB
  // key were refused naming the file alone), reading no more than 1 MiB + 1 byte of the file.
  EXPECT_TRUE(contains(refusal(std::string((1 << 20) + 1, '#')), "(the limit falls on line 1, in a comment)"));
  const std::string long_value = refusal(kScene + "integrator: " + std::string(30 << 20, 'q') + "\n");
  EXPECT_TRUE(contains(long_value, "(the limit falls on line 9, in integrator)")) << long_value;
  const std::string nested_value = refusal(kScene + "extra:\n  deeper: " + std::string(2 << 20, '7') + "x\n");
  EXPECT_TRUE(contains(nested_value, "(the limit falls on line 10, in extra/deeper)")) << nested_value;
  std::string deep = kScene;
  for (int level = 0; level < 3000; ++level) deep += std::string(2 * level, ' ') + "k" + std::to_string(level) + ":\n";
  const std::string too_deep = refusal(deep);
  EXPECT_TRUE(contains(too_deep, "in k0/.../k1020, nested 1021 levels deep)")) << too_deep;
  const std::string long_key = refusal(kScene + std::string(1 << 20, 'k') + ": 1\n");
  EXPECT_TRUE(contains(long_key, "(the limit falls on line 9, in the text 'kkkk")) << long_key;

  // A FIFO nobody writes: in a child process, so that the old behaviour (open() waits for a
  // writer for ever) fails the test instead of hanging it.
  const std::string fifo = dir_ + "/fifo.yaml";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(in_child([&] { return refused_with(fifo, "is a FIFO"); }), 0) << "-1: reading a FIFO blocked";
}

// Found by the scene-file fuzz: yaml-cpp 0.7 hands out empty documents for ever at a stray ','
// outside a flow collection (jbeder/yaml-cpp#1040; fixed upstream in LoadAll by #1319), and the
// old reader's LoadAll looped, growing without bound: simulate, ~spawn and Python hung on a
// one-byte file. Refused as malformed YAML where the parser stops moving.
TEST_F(SceneFileTest, AStrayCommaIsMalformedYamlNotAHang) {
  for (const std::string text : {",", "\n,\n", ",- scene: fixed_tip\n", "scene: fixed_tip\n---\n,"}) {
    const std::string path = write(text);
    EXPECT_EQ(in_child([&] { return refused_with(path, "malformed YAML"); }), 0) << "'" << text << "' (-1: a hang)";
  }
}

// Item 7: quotes and tags make text in YAML, never a number; rosparam hands the node a string
// for gravity: "9.8", which it refuses. The old reader took the scalar's text whatever its tag.
TEST_F(SceneFileTest, QuotedOrTaggedNumbersAreRefusedNamingTheKey) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"gravity: \"9.8\"\n", "gravity: '9.8' is quoted"},  {"mass: '0.1'\n", "mass: '0.1' is quoted"},
      {"mass: !!str 0.1\n", "mass: has the tag !!str"},    {"gravity: !foo 9.8\n", "gravity: has the tag !foo"},
      {"gravity: !!float 9.8\n", "gravity: has the tag !!float"},
      {"initial: {spin: \"150\"}\n", "initial/spin: '150' is quoted"},
  };
  std::string scene_without = kScene;
  scene_without.replace(scene_without.find("mass: 0.1\n"), 10, "");
  for (const auto& [line, expected] : cases) {
    const std::string message = refusal((contains(line, "initial") ? "scene: fixed_tip\n" : scene_without) + line);
    EXPECT_TRUE(contains(message, expected)) << line << " -> " << message;
  }
  // Names are text: plain or quoted, as both YAML versions read them alike.
  for (const std::string scene : {"scene: fixed_tip\n", "scene: \"fixed_tip\"\n", "scene: 'fixed_tip'\n"}) {
    const ParameterMap keys = read_scene_file(write(scene + "integrator: dop853\nafter_lift_off: stop\n"));
    EXPECT_EQ(keys.at("scene"), "fixed_tip");
    EXPECT_EQ(keys.at("integrator"), "dop853");
  }
  EXPECT_TRUE(contains(refusal("scene: !!str fixed_tip\n"), "scene: has the tag !!str"));
}

// A map where a value belongs, an empty map that is no section, a section written twice: each
// flattened to something other than what rosparam (PyYAML) loads for the node. `restitution: {}`
// gave no key at all (the default ran, exit 0), `foo: {}` vanished, and `initial:` twice merged
// here while PyYAML keeps the last map alone (found by the attack with seed 1206).
TEST_F(SceneFileTest, MapsOnlyWhereSectionsBelongEachOnce) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"restitution: {}\n", "restitution: a map is not a valid value; write a number"},
      {"rim_radius: {a: 1}\n", "rim_radius: a map is not a valid value; write a number"},
      {"integrator: {}\n", "integrator: a map is not a valid value"},
      {"foo: {}\n", "foo: an empty map is not a scene key or section"},
      {"initial: {}\n", "initial: given twice"},
      {"initial:\n  spin: 50.0\n", "initial: given twice"},
  };
  for (const auto& [line, expected] : cases) {
    const std::string message = refusal(kScene + line);
    EXPECT_TRUE(contains(message, expected)) << line << " -> " << message;
  }
  // A section given once, empty or not, is read as before.
  EXPECT_EQ(read_scene_file(write("scene: fixed_tip\ninitial: {}\n")).count("scene"), 1u);
  EXPECT_EQ(read_scene_file(write(kScene)).at("initial/spin"), "150.0");
}

// Item 8: plain scalars that YAML 1.1 (rosparam, PyYAML: the node) and YAML 1.2 (yaml-cpp:
// simulate, ~spawn, Python, sweeps) read differently are refused naming the key and saying why.
// The old reader passed the text to strtod: gravity: 010 ran with g = 10 in simulate and 8 in the
// node, 08 with 8 and 1e1 with 10 (both text to PyYAML, which the node refuses), 0x10 with 16
// (the prefixed forms are refused together: 0o10 is 8 in YAML 1.2 and text in 1.1, 0b11 the
// reverse), 2147483648 with 2.1e9 (rosparam cannot send an integer beyond 32 bits).
TEST_F(SceneFileTest, NumbersYaml11And12ReadDifferentlyAreRefusedNamingTheKey) {
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"010", "leading zero"},  {"08", "leading zero"},   {"0o10", "hexadecimal, octal or binary"},
      {"0x10", "hexadecimal"},  {"0b11", "binary"},       {"1_000", "underscore"},
      {"1:20", "sexagesimal"},  {"1e1", "YAML 1.1"},      {"1.0e1", "write 1.0e+1"},
      {"5e-5", "write 5.0e-5"}, {"-.5", "write -0.5"},    {"+.5e+1", "write +0.5e+1"},
      {"yes", "boolean"},       {"on", "boolean"},        {"off", "boolean"},
      {".inf", "not a finite number"}, {"-.inf", "not a finite number"}, {".nan", "not a finite number"},
      {"inf", "not a finite number"},  {"deg(30)", "rosparam converts"}, {"2147483648", "beyond 32 bits"},
      {"-99999999999", "beyond 32 bits"}, {"0x1p3", "text to YAML"}, {"-0x1.8p1", "text to YAML"}, {"infinity", "not a finite number"},
      {std::string(70, '9'), "more digits than a number needs"},
  };
  for (const auto& [value, why] : refused) {
    const std::string message = refusal(kScene + "gravity: " + value + "\n");
    EXPECT_EQ(message.rfind("gravity: '" + value.substr(0, 20), 0), 0u) << value << " -> " << message;
    EXPECT_TRUE(contains(message, why)) << value << " -> " << message;
  }
  // Text to both (mass: abc) is left to the validation, which refuses it as it refuses --set.
  for (const std::string value : {"9.8 m/s", "abc", "1,5", "2001-01-01"}) {
    const ParameterMap keys = read_scene_file(write(kScene + "gravity: " + value + "\n"));
    EXPECT_EQ(keys.at("gravity"), value);
    EXPECT_THROW(parse_scene_config(keys, true), InvalidParameter) << value;
  }
  // The forms both read as the same number keep their text (parse_number reads it).
  for (const std::string value : {"9.8", "10", "-3", "+2.5", "0", "-0.0", ".5", "1.", "4.0e-5", "1.0e+7", "1.5E+3",
                                  "2147483647", "010.5", "0.000001"}) {
    ParameterMap keys;
    EXPECT_NO_THROW(keys = read_scene_file(write(kScene + "gravity: " + value + "\n"))) << value;
    EXPECT_EQ(keys["gravity"], value);
  }
}

TEST_F(SceneFileTest, ShippedSceneFilesAreRead) {
  for (const std::string name : {"fixed_tip", "frictionless", "viscous", "extreme/stiff_friction_1e-8"}) {
    const ParameterMap keys = read_scene_file(std::string(SPINNING_TOP_SOURCE_DIR) + "/config/" + name + ".yaml");
    EXPECT_GT(keys.size(), 8u) << name;
  }
}

// A long value is not echoed in full (item 12's 20 MB message), by the reader or the validation.
TEST_F(SceneFileTest, MessagesShowAtMostTheStartOfALongValue) {
  for (const std::string value : {std::string(100000, '7'), std::string(100000, '7') + "x"}) {
    std::string message = refusal(kScene + "gravity: " + value + "\n");
    if (message.empty()) {
      try {
        parse_scene_config(read_scene_file(write(kScene + "gravity: " + value + "\n")), true);
      } catch (const InvalidParameter& e) {
        message = e.what();
      }
    }
    EXPECT_LT(message.size(), 300u) << message.substr(0, 400);
    EXPECT_TRUE(contains(message, "(" + std::to_string(value.size()) + " characters)")) << message.substr(0, 400);
  }
}

}  // namespace
}  // namespace spinning_top

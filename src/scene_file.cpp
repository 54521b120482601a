#include "spinning_top/scene_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/exceptions.h>
#include <yaml-cpp/mark.h>
#include <yaml-cpp/parser.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <regex>
#include <set>
#include <sstream>
#include <vector>

namespace spinning_top {
namespace {

// What a scene file may be (issue 19). A scene file is ~1 KB: about 25 scalar keys, at most two
// levels deep (initial/tilt). These bounds are far above that and keep every reader (simulate,
// the node's ~spawn, Python, sweeps) bounded in memory and time, whatever the file is:
//   - a regular file of at most kMaxFileBytes, read with at most kMaxFileBytes + 1 bytes (a
//     device such as /dev/zero or /dev/urandom, a FIFO or a socket is refused before it is read:
//     reading one has no end, or blocks);
//   - at most kMaxNodes YAML nodes (keys, values, maps) and maps nested kMaxDepth deep;
//   - no anchors and no aliases. yaml-cpp shares an aliased node, so the file is small but a
//     traversal visits every expansion: a 1.4 KB file of nested aliases took 3.6 GB and 20 s.
//     Refusing them outright, rather than counting expansions, is simpler and loses nothing: a
//     scene file needs none, and YAML 1.1's merge key (<<: *base), the one use of aliases in
//     parameter files, is not YAML 1.2 (rosparam merges, yaml-cpp would read a key "<<"), so a
//     file with one would give the node and simulate different tops.
// The file is read as a stream of parser events (no node tree is built), so nothing is expanded
// and the limits apply while parsing.
constexpr std::size_t kMaxFileBytes = 1 << 20;  // 1 MiB
constexpr std::size_t kMaxNodes = 10000;
constexpr int kMaxDepth = 16;
/// The longest text read as a number: 17 significant digits, a sign, a point and an exponent
/// need 25; a few more leave room for zeros written out (0.000001).
constexpr std::size_t kMaxNumberCharacters = 64;

std::string brief(const std::string& text, std::size_t limit = 40) { return brief_text(text, limit); }

/// A path as shown in a message (a path may be long; its end is the file's name).
std::string shown_path(const std::string& path) {
  constexpr std::size_t kLimit = 160;
  if (path.size() <= kLimit) return brief(path, kLimit);
  return brief(path.substr(0, 40), 40) + "..." + brief(path.substr(path.size() - 117), kLimit);
}

class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) close(fd_);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

std::string kind_of(mode_t mode) {
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

void require_regular(const std::string& path, const struct stat& st) {
  if (S_ISDIR(st.st_mode))
    throw SceneFileError("'" + shown_path(path) + "' is a directory; give a scene file (e.g. config/fixed_tip.yaml)");
  if (!S_ISREG(st.st_mode))
    throw SceneFileError("'" + shown_path(path) + "' is " + kind_of(st.st_mode) +
                         ", not a regular file; give a scene file (e.g. config/fixed_tip.yaml)");
}

/// Where the first kMaxFileBytes + 1 bytes of a file (head) pass the limit, so that the refusal
/// points at what grew: " (the limit falls on line 31, in integrator)" for a 30 MB value, "in
/// k0/.../k1023, nested 1024 levels deep" for deep maps, "in a comment"; "" if head ends first.
/// The keys come from the indentation of block maps alone (a file refused is not parsed): enough
/// to point at the culprit, not a reading of the file.
std::string where_the_limit_falls(const std::string& head) {
  if (head.size() <= kMaxFileBytes) return "";
  constexpr std::size_t kKeyCharacters = 80;  // kept of each key (brief() shows 40)
  struct Level {
    std::size_t indent;
    std::string key;
  };
  std::vector<Level> path;
  std::size_t line_start = 0, line_number = 1;
  for (;;) {
    std::size_t line_end = head.find('\n', line_start);
    if (line_end == std::string::npos) line_end = head.size();
    const std::size_t text = std::min(head.find_first_not_of(' ', line_start), line_end);
    const std::size_t indent = text - line_start;
    const bool comment = text < line_end && head[text] == '#';
    bool has_key = false;
    if (text < line_end && !comment && head[text] != '-') {
      // A block map's "key:" or "key: value" (searched within the line only: linear in the head).
      const std::size_t colon = static_cast<std::size_t>(
          std::find(head.begin() + static_cast<std::ptrdiff_t>(text), head.begin() + static_cast<std::ptrdiff_t>(line_end), ':') -
          head.begin());
      has_key = colon < line_end && (colon + 1 == line_end || head[colon + 1] == ' ' || head[colon + 1] == '\r');
      if (has_key) {
        while (!path.empty() && path.back().indent >= indent) path.pop_back();
        path.push_back({indent, head.substr(text, std::min(colon - text, kKeyCharacters))});
      }
    }
    if (line_end >= kMaxFileBytes) {
      const std::string where = " (the limit falls on line " + std::to_string(line_number) + ", ";
      if (comment) return where + "in a comment)";
      if (!has_key && text < line_end)  // a line without "key:" in its first MiB (a 1 MB key)
        return where + "in the text '" + brief(head.substr(text, kKeyCharacters), 20) + "')";
      if (path.empty()) return where + "before any key)";
      std::string keys;
      if (path.size() <= 3) {
        for (const Level& level : path) keys += (keys.empty() ? "" : "/") + brief(level.key);
      } else {
        keys = brief(path.front().key) + "/.../" + brief(path.back().key) + ", nested " +
               std::to_string(path.size()) + " levels deep";
      }
      return where + "in " + keys + ")";
    }
    line_start = line_end + 1;
    ++line_number;
  }
}

std::string too_large(const std::string& path, const std::string& head) {
  return "'" + shown_path(path) + "' is larger than " + std::to_string(kMaxFileBytes >> 20) + " MiB" +
         where_the_limit_falls(head) + "; a scene file is a few KB of key: value lines";
}

/// The file's text: a regular file (also through a symbolic link) of at most kMaxFileBytes.
std::string read_bounded(const std::string& path) {
  struct stat st {};
  // stat first: opening a FIFO would block and opening a device may act on it.
  if (stat(path.c_str(), &st) != 0)
    throw SceneFileError("cannot read '" + shown_path(path) + "': " + std::strerror(errno));
  require_regular(path, st);
  // O_NONBLOCK: should the path have become a FIFO since, open does not wait for a writer.
  const FileDescriptor fd(open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC));
  if (fd.get() < 0) throw SceneFileError("cannot read '" + shown_path(path) + "': " + std::strerror(errno));
  if (fstat(fd.get(), &st) != 0)
    throw SceneFileError("cannot read '" + shown_path(path) + "': " + std::strerror(errno));
  require_regular(path, st);
  // At most one byte more than the limit (also from a larger file: the refusal says where in it
  // the limit falls), and a file that grows, or a /proc file whose size reads 0, stops there too.
  std::string text(kMaxFileBytes + 1, '\0');
  std::size_t length = 0;
  while (length < text.size()) {
    const ssize_t n = read(fd.get(), &text[length], text.size() - length);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw SceneFileError("cannot read '" + shown_path(path) + "': " + std::strerror(errno));
    if (n == 0) break;
    length += static_cast<std::size_t>(n);
  }
  if (length > kMaxFileBytes) throw SceneFileError(too_large(path, text));
  text.resize(length);
  return text;
}

bool matches(const std::string& text, const std::regex& pattern) { return std::regex_match(text, pattern); }

std::regex pattern(const char* text) { return std::regex(text, std::regex::extended); }

/// A number of the forms YAML 1.1 reads as text (1e5, 1.5e5, 1e-5, -.5) as both read it: with
/// a digit before the point, a point before the exponent and a sign in it (1.0e+5, -0.5).
std::string both_readings(const std::string& text) {
  std::size_t i = 0;
  std::string sign;
  if (i < text.size() && (text[i] == '-' || text[i] == '+')) sign = text[i++];
  std::string mantissa;
  while (i < text.size() && text[i] != 'e' && text[i] != 'E') mantissa += text[i++];
  if (mantissa.empty() || mantissa[0] == '.') mantissa = "0" + mantissa;
  if (mantissa.find('.') == std::string::npos) mantissa += ".0";
  if (i == text.size()) return sign + mantissa;
  ++i;  // the e
  std::string exponent_sign = "+";
  if (i < text.size() && (text[i] == '-' || text[i] == '+')) exponent_sign = text[i++];
  return sign + mantissa + "e" + exponent_sign + text.substr(i);
}

/// Why YAML 1.1 (rosparam, PyYAML: how the node's launch file loads a scene file) and YAML 1.2
/// (yaml-cpp: simulate, ~spawn, Python, sweeps) would not read the plain scalar `text` as the
/// same number; "" if both read it as the same decimal number, which parse_number() then reads
/// (strtod) as the double Python's float() gives, or both read it as text that strtod does not
/// read either (mass: abc), which parse_number() refuses as it refuses --set mass=abc.
///
/// Accepted, the forms on which both agree (YAML 1.1 as PyYAML implements it):
///   integers   [-+]?(0|[1-9][0-9]*), within 32 bits (rosparam sends ints over XML-RPC, whose
///              int is 32-bit: a larger one fails `rosparam load`)
///   decimals   [-+]?[0-9]+.[0-9]*  and  .[0-9]+ (no sign: YAML 1.1 reads -.5 as text),
///              either with an exponent [eE][-+][0-9]+ (signed: YAML 1.1 reads 1e5 and 1.0e5
///              as text)
std::string yaml_number_problem(const std::string& text) {
  // Before any pattern: std::regex recurses per character, and no number needs this many (text
  // that is no number at all is left to the validation, which says so).
  if (text.size() > kMaxNumberCharacters) {
    char* end = nullptr;
    std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0') return "";
    return "'" + brief(text) + "' has more digits than a number needs (a double has at most 17 significant digits)";
  }
  static const std::regex kInteger = pattern("^[-+]?(0|[1-9][0-9]*)$");
  static const std::regex kDecimal = pattern("^[-+]?[0-9]+\\.[0-9]*([eE][-+][0-9]+)?$");
  static const std::regex kLeadingDot = pattern("^\\.[0-9]+([eE][-+][0-9]+)?$");
  static const std::regex kExponentOrDotUnsigned = pattern("^[-+]?[0-9]+(\\.[0-9]*)?[eE][-+]?[0-9]+$");
  static const std::regex kSignedLeadingDot = pattern("^[-+]?\\.[0-9]+([eE][-+]?[0-9]+)?$");
  static const std::regex kLeadingZero = pattern("^[-+]?0[0-9_]+$");
  static const std::regex kPrefixed = pattern("^[-+]?0[xXoObB][0-9a-fA-F_]*$");
  static const std::regex kSexagesimal = pattern("^[-+]?[0-9][0-9_]*(:[0-5]?[0-9])+(\\.[0-9_]*)?$");
  static const std::regex kUnderscored = pattern("^[-+]?[0-9_.]+([eE][-+]?[0-9]+)?$");
  static const std::regex kInfinityOrNaN = pattern("^[-+]?\\.?([iI]nf|INF|[iI]nfinity|[nN]a[nN]|NAN)$");
  static const std::regex kBoolean = pattern("^(y|Y|yes|Yes|YES|n|N|no|No|NO|true|True|TRUE|false|False|FALSE|on|On|ON|off|Off|OFF)$");
  static const std::regex kAngle = pattern("^(deg|rad)\\(.*\\)$");
  const std::string quoted = "'" + brief(text) + "'";
  if (matches(text, kInteger)) {
    const std::string digits = text.find_first_of("+-") == 0 ? text.substr(1) : text;
    if (digits.size() > 10 || std::stod(digits) > 2147483647.0)
      return quoted + " is an integer beyond 32 bits, which rosparam cannot hand to the node (XML-RPC integers are "
                      "32-bit): write it with a decimal point, e.g. " + (text.size() <= 20 ? text + ".0" : "1.0e+20");
    return "";
  }
  if (matches(text, kDecimal) || matches(text, kLeadingDot))
    return "";
  const std::string one_one = " YAML 1.1 (rosparam: the node's launch file) and YAML 1.2 (simulate, ~spawn, Python) ";
  if (matches(text, kExponentOrDotUnsigned) || matches(text, kSignedLeadingDot))
    return quoted + ":" + one_one + "read it differently (YAML 1.1 reads it as text: there an exponent needs a " +
           "point and a sign, and a leading point no sign): write " + both_readings(text);
  if (matches(text, kLeadingZero))
    return quoted + " has a leading zero:" + one_one + "read it differently (YAML 1.1: octal, 010 is 8; YAML 1.2: "
                    "decimal, 10): write the number without leading zeros";
  if (matches(text, kPrefixed))
    return quoted + " is hexadecimal, octal or binary:" + one_one + "read these forms differently: write a decimal number";
  if (matches(text, kSexagesimal))
    return quoted + " is sexagesimal (base 60) in YAML 1.1 (1:20 is 80) and text in YAML 1.2: write a decimal number";
  if (text.find('_') != std::string::npos && matches(text, kUnderscored))
    return quoted + " has an underscore: YAML 1.1 reads 1_000 as 1000, YAML 1.2 as text: write it without underscores";
  if (matches(text, kInfinityOrNaN))
    return quoted + " is not a finite number";
  if (matches(text, kBoolean))
    return quoted + " is a boolean in YAML 1.1 (rosparam) and text in YAML 1.2, not a number";
  if (matches(text, kAngle))
    return quoted + " is an angle that rosparam converts (deg(...), rad(...)) and YAML 1.2 reads as text: write the "
                    "number of radians";
  // Text to both YAML versions: the validation refuses it as not a number (parse_number), unless
  // strtod would read it whole (0x1p3, infinity), which YAML does not.
  char* end = nullptr;
  std::strtod(text.c_str(), &end);
  if (end != text.c_str() && *end == '\0')
    return quoted + " is text to YAML (1.1 and 1.2), not a number: write a decimal number";
  return "";
}

/// The scene key `key` (a value: a number or a name), nullptr if there is none.
const ParameterSpec* spec_of(const std::string& key) {
  for (const ParameterSpec& spec : parameter_specs())
    if (key == spec.key) return &spec;
  return nullptr;
}

/// Whether `key` is a configuration key whose value is a number (not a name such as scene).
bool numeric_key(const std::string& key) {
  const ParameterSpec* spec = spec_of(key);
  return spec != nullptr && !spec->text;
}

/// Whether scene keys lie under `prefix` (initial: ...): a map belongs there.
bool section(const std::string& prefix) {
  for (const ParameterSpec& spec : parameter_specs()) {
    const std::string key = spec.key;
    if (key.size() > prefix.size() && key.compare(0, prefix.size(), prefix) == 0 && key[prefix.size()] == '/') return true;
  }
  return false;
}

/// The tag as written: !!str for tag:yaml.org,2002:str.
std::string shown_tag(const std::string& tag) {
  const std::string core = "tag:yaml.org,2002:";
  return brief(tag.rfind(core, 0) == 0 ? "!!" + tag.substr(core.size()) : tag);
}

/// Where each document starts: yaml-cpp 0.7 can hand out documents for ever without moving on
/// (a stray ',' at the top level: jbeder/yaml-cpp#1040, fixed upstream by #1319 in LoadAll); a
/// document that starts where the previous one did is that, and refused as malformed YAML.
class DocumentStarts {
 public:
  explicit DocumentStarts(const std::string& file) : file_(file) {}
  void start(const YAML::Mark& mark) {
    if (count_ > 0 && mark.pos == last_.pos)
      throw SceneFileError(file_ + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1) +
                           ": malformed YAML: the parser cannot read past this point (a stray ',' or the like)");
    last_ = mark;
    ++count_;
  }
  std::size_t count() const { return count_; }

 private:
  std::string file_;
  YAML::Mark last_;
  std::size_t count_ = 0;
};

/// Builds the flat key -> text map from the parser's events, refusing what a scene file is not.
class SceneFileHandler : public YAML::EventHandler {
 public:
  SceneFileHandler(const std::string& file, ParameterMap& out, DocumentStarts& starts)
      : file_(shown_path(file)), out_(out), starts_(starts) {}

  void OnDocumentStart(const YAML::Mark& mark) override { starts_.start(mark); }
  void OnDocumentEnd() override {}

  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    visit(mark, anchor);
    if (frames_.empty()) return;  // an empty document: the missing keys are reported later
    Frame& frame = frames_.back();
    if (frame.expecting_key) fail(mark, "a key is empty (keys must be plain names)");
    throw SceneFileError(value_key() + ": has no value" + where(mark));
  }

  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override {
    count(mark);
    refuse_reference(mark, "an alias (*name)");
  }

  void OnAnchor(const YAML::Mark& mark, const std::string& name) override {
    refuse_reference(mark, "an anchor (&" + brief(name) + ")");
  }

  void OnScalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor, const std::string& value) override {
    visit(mark, anchor);
    if (frames_.empty()) fail(mark, "the top level must be a map of key: value");
    Frame& frame = frames_.back();
    if (frame.expecting_key) {
      if (tag != "?" && tag != "!") fail(mark, "a key has the tag " + shown_tag(tag) + " (keys must be plain names)");
      if (value == "<<")
        fail(mark, "a merge key (<<) is YAML 1.1 only (rosparam merges, YAML 1.2 reads a key '<<'); write the keys out");
      frame.key = value;
      frame.expecting_key = false;
      frame.has_entries = true;
      return;
    }
    const std::string key = value_key();
    frame.expecting_key = true;
    if (tag != "?" && tag != "!")
      throw SceneFileError(key + ": has the tag " + shown_tag(tag) + "; scene files take no tags: write the value alone" +
                           where(mark));
    if (numeric_key(key)) {
      if (tag == "!")
        throw SceneFileError(key + ": '" + brief(value) +
                             "' is quoted, which makes it text in YAML, not a number: write it without quotes" +
                             where(mark));
      const std::string problem = yaml_number_problem(value);
      if (!problem.empty()) throw SceneFileError(key + ": " + problem + where(mark));
    }
    if (!out_.emplace(key, value).second) throw SceneFileError(key + ": given twice in " + file_);
  }

  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    visit(mark, anchor);
    if (frames_.empty()) fail(mark, "the top level must be a map of key: value");
    if (frames_.back().expecting_key) fail(mark, "a key is a list (keys must be plain names)");
    throw SceneFileError(value_key() + ": a list is not a valid value (in " + file_ + ")");
  }
  void OnSequenceEnd() override {}

  void OnMapStart(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    visit(mark, anchor);
    if (tag != "?") fail(mark, "a map has the tag " + shown_tag(tag) + "; scene files take no tags");
    std::string prefix;
    if (!frames_.empty()) {
      if (frames_.back().expecting_key) fail(mark, "a key is a map (keys must be plain names)");
      prefix = value_key();
      // A map where a value belongs: flattened, `restitution: {}` gave no key at all and the
      // default ran; `restitution: {a: 1}` would be refused as restitution/a, naming no value.
      if (const ParameterSpec* spec = spec_of(prefix))
        throw SceneFileError(prefix + ": a map is not a valid value; write " +
                             (spec->text ? "the value" : "a number") + where(mark));
      // A section written twice: flattened, both would merge, while rosparam (PyYAML) keeps the
      // last map alone: one file, two scenes.
      if (!maps_seen_.insert(prefix).second) throw SceneFileError(prefix + ": given twice" + where(mark));
    }
    if (static_cast<int>(frames_.size()) >= kMaxDepth)
      fail(mark, "maps nested more than " + std::to_string(kMaxDepth) + " deep; a scene file nests one level (initial:)");
    frames_.push_back({prefix, "", true});
  }

  void OnMapEnd() override {
    // An empty map that is no section of scene keys (`foo: {}`) would vanish in the flat map:
    // refused as any unknown key is, rather than read as nothing.
    const Frame ended = frames_.back();
    frames_.pop_back();
    if (!frames_.empty() && !ended.has_entries && !section(ended.prefix))
      throw SceneFileError(ended.prefix + ": an empty map is not a scene key or section (in " + file_ + ")");
    if (!frames_.empty()) frames_.back().expecting_key = true;
  }

 private:
  struct Frame {
    std::string prefix;  ///< the flattened key of this map ("" at the top)
    std::string key;     ///< the key whose value comes next
    bool expecting_key;
    bool has_entries = false;  ///< a key was read in this map
  };

  std::string value_key() const {
    const Frame& frame = frames_.back();
    return brief(frame.prefix.empty() ? frame.key : frame.prefix + "/" + frame.key, 80);
  }

  std::string where(const YAML::Mark& mark) const {
    return " (in " + file_ + ":" + std::to_string(mark.line + 1) + ")";
  }

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& what) const {
    throw SceneFileError(file_ + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1) + ": " + what);
  }

  /// An anchor or an alias, named by the key whose value it is (else by where it is).
  void refuse_reference(const YAML::Mark& mark, const std::string& what) const {
    const std::string why = what + ": scene files take no anchors or aliases (YAML 1.1 and 1.2 merge them "
                                   "differently, and an alias can expand without bound); write each value out";
    if (!frames_.empty() && !frames_.back().expecting_key) throw SceneFileError(value_key() + ": " + why + where(mark));
    fail(mark, why);
  }

  void count(const YAML::Mark& mark) {
    if (++nodes_ > kMaxNodes)
      fail(mark, "more than " + std::to_string(kMaxNodes) + " YAML nodes; a scene file has a few dozen");
  }

  void visit(const YAML::Mark& mark, YAML::anchor_t anchor) {
    count(mark);
    if (anchor != YAML::NullAnchor) refuse_reference(mark, "an anchor (&name)");
  }

  std::string file_;
  ParameterMap& out_;
  DocumentStarts& starts_;
  std::vector<Frame> frames_;
  std::set<std::string> maps_seen_;  ///< the prefixes of the maps read so far
  std::size_t nodes_ = 0;
};

/// Counts the documents after the first without looking into them (bounded by the file's size).
class DocumentCounter : public YAML::EventHandler {
 public:
  explicit DocumentCounter(DocumentStarts& starts) : starts_(starts) {}
  void OnDocumentStart(const YAML::Mark& mark) override { starts_.start(mark); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}

 private:
  DocumentStarts& starts_;
};

}  // namespace

ParameterMap read_scene_file(const std::string& path) {
  std::istringstream text(read_bounded(path));
  ParameterMap values;
  try {
    YAML::Parser parser(text);
    DocumentStarts starts(shown_path(path));
    SceneFileHandler handler(path, values, starts);
    if (!parser.HandleNextDocument(handler)) return values;  // an empty file
    // One document: a second one (after ---) would otherwise be ignored without a word.
    DocumentCounter counter(starts);
    while (parser.HandleNextDocument(counter)) {
    }
    if (starts.count() > 1)
      throw SceneFileError(shown_path(path) + ": has " + std::to_string(starts.count()) +
                           " YAML documents (separated by ---); a scene file is one");
  } catch (const YAML::Exception& e) {
    std::ostringstream where;
    where << shown_path(path) << ":" << e.mark.line + 1 << ":" << e.mark.column + 1 << ": malformed YAML: " << brief(e.msg, 200);
    throw SceneFileError(where.str());
  }
  return values;
}

}  // namespace spinning_top

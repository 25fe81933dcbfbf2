// The docs against the topics the code declares (runtime/include/lockstep/runtime/*.h:
// Topic<msg::T> kX{"name", QosKind::kFamily} and the per-camera topic names):
// docs/topics.md's table has every declared topic with its type and QoS family and no other;
// docs/architecture.md's process table names only declared types and a writer for each;
// no doc carries merge-conflict markers.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
const fs::path kSource = LOCKSTEP_SOURCE_DIR;

std::string Read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// QosKind::kLargeImage -> large_image, as docs/topics.md names the families.
std::string Family(const std::string& kind) {
  std::string out;
  for (char c : kind) {
    if (std::isupper(static_cast<unsigned char>(c)) && !out.empty()) out += '_';
    out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return out;
}

struct Declared {
  std::string type, family;
};

// name -> type and family, from the runtime's headers; per-camera names as "<prefix>/<sensor id>".
std::map<std::string, Declared> DeclaredTopics() {
  std::map<std::string, Declared> out;
  const std::regex fixed(R"re(Topic<msg::(\w+)>\s+k\w+\{"(lockstep/[^"]+)",\s*QosKind::k(\w+)\})re");
  const std::regex per_sensor(R"re(return "(lockstep/[^"]+)/" \+ std::to_string\(sensor\))re");
  for (const auto& e : fs::directory_iterator(kSource / "runtime/include/lockstep/runtime")) {
    const std::string text = Read(e.path());
    for (std::sregex_iterator it(text.begin(), text.end(), fixed), end; it != end; ++it) {
      out[(*it)[2]] = Declared{(*it)[1], Family((*it)[3])};
    }
    for (std::sregex_iterator it(text.begin(), text.end(), per_sensor), end; it != end; ++it) {
      out[std::string((*it)[1]) + "/<sensor id>"] = Declared{};
    }
  }
  return out;
}

// The message types of the per-camera topics (render/service: Image, or LargeImage over its bound).
const char* const kPerCameraTypes[] = {"Image", "LargeImage"};

// The rows of the "## Topics" table: name -> (type, family).
std::map<std::string, Declared> DocumentedTopics() {
  std::map<std::string, Declared> out;
  std::istringstream in(Read(kSource / "docs/topics.md"));
  std::string line;
  bool in_section = false;
  const std::regex row(R"re(^\| `(lockstep/[^`]+)` \| `(\w+)`[^|]*\| (\w+) \|)re");
  while (std::getline(in, line)) {
    if (line.rfind("## ", 0) == 0) in_section = line == "## Topics";
    std::smatch m;
    if (in_section && std::regex_search(line, m, row)) {
      EXPECT_EQ(out.count(m[1]), 0u) << "docs/topics.md lists " << m[1] << " twice";
      out[m[1]] = Declared{m[2], m[3]};
    }
  }
  return out;
}

TEST(TopicsDoc, TheTableListsEveryDeclaredTopicWithItsTypeAndFamily) {
  const auto declared = DeclaredTopics();
  const auto documented = DocumentedTopics();
  ASSERT_GT(declared.size(), 20u) << "the topic declarations were not found";
  for (const auto& [name, d] : declared) {
    auto it = documented.find(name);
    if (it == documented.end()) {
      ADD_FAILURE() << name << " is declared in runtime/include/lockstep/runtime but not in docs/topics.md's table";
      continue;
    }
    if (d.type.empty()) continue;  // a per-camera topic: its type depends on the image size
    EXPECT_EQ(it->second.type, d.type) << name;
    EXPECT_EQ(it->second.family, d.family) << name;
  }
  for (const auto& [name, d] : documented) {
    EXPECT_TRUE(declared.count(name)) << "docs/topics.md lists " << name << ", which no header declares";
  }
}

// Backticked CamelCase names in a table cell ("`Tick`, `GroundState` of frame k-1").
std::vector<std::string> TypesIn(const std::string& cell) {
  std::vector<std::string> out;
  const std::regex name("`([A-Z][A-Za-z0-9]+)`");
  for (std::sregex_iterator it(cell.begin(), cell.end(), name), end; it != end; ++it) out.push_back((*it)[1]);
  return out;
}

TEST(TopicsDoc, TheProcessTableNamesDeclaredTypesAndAWriterForEach) {
  std::set<std::string> declared(std::begin(kPerCameraTypes), std::end(kPerCameraTypes));
  for (const auto& [name, d] : DeclaredTopics()) {
    if (!d.type.empty()) declared.insert(d.type);
  }
  std::istringstream in(Read(kSource / "docs/architecture.md"));
  std::string line;
  bool in_section = false;
  std::set<std::string> written;
  std::string below;  // the paragraph under the table
  size_t rows = 0;
  while (std::getline(in, line)) {
    if (line.rfind("## ", 0) == 0) in_section = line == "## Processes";
    if (!in_section) continue;
    if (line.rfind("| ", 0) == 0 && line.find("`") != std::string::npos) {
      // | process | owns today | publishes | reads |
      std::vector<std::string> cells;
      std::string cell;
      std::istringstream row(line.substr(1));
      while (std::getline(row, cell, '|')) cells.push_back(cell);
      ASSERT_GE(cells.size(), 4u) << line;
      ++rows;
      for (size_t c : {size_t{2}, size_t{3}}) {
        for (const auto& t : TypesIn(cells[c])) {
          EXPECT_TRUE(declared.count(t)) << "docs/architecture.md's process table names `" << t << "`, which no topic carries";
          if (c == 2) written.insert(t);
        }
      }
    } else if (line.rfind("Every service also writes", 0) == 0) {
      below = line;
    } else if (!below.empty() && !line.empty()) {
      below += " " + line;
    } else if (!below.empty()) {
      // What every service writes, below the table: up to "; it reads".
      for (const auto& t : TypesIn(below.substr(0, below.find("; it reads")))) written.insert(t);
      below.clear();
    }
  }
  ASSERT_GT(rows, 5u) << "the process table was not found";
  for (const auto& t : declared) {
    EXPECT_TRUE(written.count(t)) << "no process of docs/architecture.md's table (or the line below it) publishes `" << t << "`";
  }
}

TEST(TopicsDoc, NoDocCarriesMergeConflictMarkers) {
  for (const auto& e : fs::directory_iterator(kSource / "docs")) {
    if (e.path().extension() != ".md") continue;
    std::istringstream in(Read(e.path()));
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      EXPECT_FALSE(line.rfind("<<<<<<< ", 0) == 0 || line.rfind(">>>>>>> ", 0) == 0)
          << e.path().filename().string() << ":" << n << ": " << line;
    }
  }
}

}  // namespace

// docs/topics.md's topic table against the topics the code declares
// (runtime/include/lockstep/runtime/*.h: Topic<msg::T> kX{"name", QosKind::kFamily} and
// the per-camera topic names): every declared topic has its row with the declared type and
// QoS family, every row names a declared topic, and no doc carries merge-conflict markers.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

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

#include "config/yaml_reader.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>

#include "tests/support/paths.hpp"

namespace leakmon::config {
namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ConfigNode, UnknownKeyNamesFileLineColumnAndAllowedKeys) {
  auto root = ConfigNode::load_string("period_ms: 2\nperiode: 3\n", "demo.yaml");
  std::string message = error_of([&] { root.expect_keys({"period_ms", "priority"}); });
  EXPECT_EQ(message,
            "demo.yaml:2:1: periode: unknown key 'periode' (allowed: period_ms, priority)");
}

TEST(ConfigNode, NestedPathAndRangeError) {
  auto root = ConfigNode::load_string("loop:\n  groups:\n    - period_ms: -1\n", "c.yaml");
  auto group = root.at("loop").at("groups").items().at(0);
  std::string message = error_of([&] { group.get_double("period_ms", 0.1, 100.0); });
  EXPECT_EQ(message, "c.yaml:3:18: loop.groups[0].period_ms: value -1 is out of range [0.1, 100]");
}

TEST(ConfigNode, WrongTypeSaysWhatWasExpected) {
  auto root = ConfigNode::load_string("port: ninety\nenabled: maybe\nlist: [1, 2]\n", "x.yaml");
  EXPECT_EQ(error_of([&] { root.get_int("port", 1, 65535); }),
            "x.yaml:1:7: port: expected an integer, got 'ninety'");
  EXPECT_EQ(error_of([&] { root.get_bool("enabled", false); }),
            "x.yaml:2:10: enabled: expected true or false, got 'maybe'");
  EXPECT_NE(error_of([&] { root.get_double("list"); }).find("expected a number"),
            std::string::npos);
}

TEST(ConfigNode, MissingRequiredKeyAndDefaults) {
  auto root = ConfigNode::load_string("a: 1\n", "m.yaml");
  EXPECT_NE(error_of([&] { root.get_string("name"); }).find("missing required key 'name'"),
            std::string::npos);
  EXPECT_EQ(root.get_double("b", 2.5, 0, 10), 2.5);
  EXPECT_EQ(root.get_int("a", 7, 0, 10), 1);
  EXPECT_EQ(root.get_choice("mode", {"x", "y"}, "y"), "y");
}

TEST(ConfigNode, ChoiceListsTheValidValues) {
  auto root = ConfigNode::load_string("mode: sym\n", "m.yaml");
  EXPECT_EQ(error_of([&] {
              root.get_choice("mode", {"symmetric", "zero"}, "symmetric");
            }),
            "m.yaml:1:7: mode: 'sym' is not one of: symmetric, zero");
}

TEST(ConfigNode, SyntaxErrorHasLocation) {
  std::string message = error_of([] { ConfigNode::load_string("a: [1, 2\nb: 3\n", "bad.yaml"); });
  EXPECT_EQ(message.rfind("bad.yaml:", 0), 0u) << message;
  EXPECT_NE(message.find(':', 9), std::string::npos);
}

// Issue 25: a bad indentation gave a bare `end of map not found`. The message now says what is
// probably wrong, and keeps the parser's words and the location.
TEST(ConfigNode, SyntaxErrorsSayWhatIsProbablyWrong) {
  const auto message = [](const std::string& text) {
    return error_of([&] { ConfigNode::load_string(text, "rig.yaml"); });
  };
  // A key indented one space less than its siblings.
  EXPECT_EQ(message("metrics:\n  port: 9187\n address: 127.0.0.1\n"),
            "rig.yaml:3:2: probably wrong indentation: line 3 starts at column 2, but the blocks "
            "above start at columns 1, 3; entries of one mapping or list start in the same column "
            "(YAML parser: end of map not found)");
  // Inside a list item.
  const std::string in_list =
      message("drivers:\n  - name: rig\n    type: sim\n   seed: 7\nactuators: []\n");
  EXPECT_NE(in_list.find("rig.yaml:4:4: probably wrong indentation: line 4 starts at column 4, "
                         "but the blocks above start at columns 1, 3, 5"),
            std::string::npos)
      << in_list;
  // Indented deeper than its siblings: it continues the value above.
  const std::string deeper = message("drivers:\n  - name: rig\n    type: sim\n      seed: 7\n");
  EXPECT_NE(deeper.find("rig.yaml:4:11: probably wrong indentation: line 4 starts at column 7, "
                        "deeper than line 3 (column 5)"),
            std::string::npos)
      << deeper;
  // Tabs.
  const std::string tab = message("drivers:\n  - name: rig\n\ttype: sim\n");
  EXPECT_NE(tab.find("rig.yaml:3:1: line 3 is indented with a tab: YAML indents with spaces only"),
            std::string::npos)
      << tab;
  // An unquoted ': ' in a value; an unclosed inline mapping.
  EXPECT_NE(message("message: leak: big\n").find("a value that contains ': ' must be quoted"),
            std::string::npos);
  EXPECT_NE(message("channels: {p1: rig.p1, p2: rig.p2\nevents: {}\n")
                .find("an inline mapping opened with '{' is not closed with '}'"),
            std::string::npos);
  EXPECT_NE(message("a: [1, 2\nb: 3\n").find("an inline list opened with '[' is not closed"),
            std::string::npos);
}

TEST(ConfigNode, MissingFileIsAnError) {
  EXPECT_EQ(error_of([] { ConfigNode::load_file("/nonexistent/leakmon.yaml"); }),
            "/nonexistent/leakmon.yaml: cannot open file");
}

TEST(ConfigNode, LoadsFromFileWithItsName) {
  std::string dir = test::scratch_dir("ConfigNode_LoadsFromFile");
  std::string path = dir + "/f.yaml";
  std::ofstream(path) << "x: 1e-12\ny: +3\n";
  auto root = ConfigNode::load_file(path);
  EXPECT_DOUBLE_EQ(root.get_double("x"), 1e-12);
  EXPECT_EQ(root.get_int("y", 0, 5), 3);
  EXPECT_EQ(root.at("x").location(), path + ":1:4");
}

TEST(ConfigNode, NonFiniteNumbersRejected) {
  auto root = ConfigNode::load_string("x: .inf\ny: nan\n", "n.yaml");
  EXPECT_NE(error_of([&] { root.get_double("x"); }).find("finite"), std::string::npos);
  EXPECT_NE(error_of([&] { root.get_double("y"); }).find("finite"), std::string::npos);
}

TEST(ConfigNode, DuplicateKeysAreErrorsAtTheSecondOccurrence) {
  EXPECT_EQ(error_of([] { ConfigNode::load_string("a: 1\nb: {x: 1, x: 2}\n", "f.yaml"); }),
            "f.yaml:2:11: duplicate key 'x' (first given at line 2, column 5); only one of them "
            "would take effect");
  EXPECT_EQ(error_of([] { ConfigNode::load_string("a: 1\nb:\n  c: 1\na: 2\n", "f.yaml"); }),
            "f.yaml:4:1: duplicate key 'a' (first given at line 1, column 1); only one of them "
            "would take effect");
  EXPECT_EQ(error_of([] { ConfigNode::load_string("- {x: 1}\n- {x: 2}\n", "f.yaml"); }),
            "no error");
}

// Two configurations pasted into one file: yaml-cpp would read the first and drop the rest.
TEST(ConfigNode, ASecondDocumentIsAnErrorNotIgnored) {
  EXPECT_EQ(error_of([] { ConfigNode::load_string("a: 1\n---\na: 2\n", "f.yaml"); }),
            "f.yaml:2:1: a second YAML document ('---'); a configuration is one document (only "
            "the first would take effect)");
  EXPECT_EQ(error_of([] { ConfigNode::load_string("a: 1\n...\nb: 2\n", "f.yaml"); }),
            "f.yaml:3:1: content after the end of the YAML document ('...'); a configuration is "
            "one document");
  // One document, however it is marked: a leading '---', a directive, comments, a closing
  // '...', a '---' inside a value's text (not at column 0).
  for (const char* one : {"---\na: 1\n", "%YAML 1.2\n---\na: 1\n...\n", "# c\n---  # c\na: 1\n",
                          "a: |\n  ---\n  x\n", "a: 1\n...\n# the end\n", "a: '--- x'\n"}) {
    EXPECT_EQ(error_of([&] { ConfigNode::load_string(one, "f.yaml"); }), "no error") << one;
  }
  EXPECT_NE(error_of([] {
              ConfigNode::load_string("a: 1\r\n---\r\nb: 2\r\n", "f.yaml");
            }).find("f.yaml:2:1: a second YAML document"),
            std::string::npos);
}

// Found by fuzz/config_reader_fuzz.cpp: a list as a key escaped as a yaml-cpp exception, and a
// malformed stream made the parser report documents without end.
TEST(ConfigNode, FuzzFindingsStayConfigErrors) {
  const ConfigNode root = ConfigNode::load_string("? [a, b]\n: 1\n", "f.yaml");
  EXPECT_EQ(error_of([&] { root.expect_keys({"a"}); }), "f.yaml:1:3: a key must be plain text");
  EXPECT_EQ(error_of([&] { (void)root.entries(); }), "f.yaml:1:3: a key must be plain text");
  EXPECT_NO_THROW(
      ConfigNode::load_string(", seed: 8}]\n: metrt: 1}\nmetr\xe9"
                              "cs: {port: 2}\n",
                              "f.yaml"));
}

}  // namespace
}  // namespace leakmon::config

#pragma once
/// \file YAML scalars as the scene validator and the study plan read and show them: numbers and
/// integers parsed strictly (the whole text, finite), quoted scalars kept as text, and the words a
/// message uses for what a document holds; key paths.
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace crackle::scene {

/// The whole of `text` as a finite number (strtod syntax); false otherwise.
bool parse_number(const std::string& text, double& value);
/// The whole of `text` as a base-10 integer; false otherwise.
bool parse_integer(const std::string& text, long long& value);
/// A scalar written in quotes ('1.0' is text, not a number).
bool is_quoted(const YAML::Node& node);
/// How a message shows what the document holds: "-2e11", "true", "'abc'", "a map", "an empty map",
/// "a list of 2 entries", "nothing".
std::string describe_node(const YAML::Node& node);
/// 1-based line of a node in its file, or -1 when unknown.
int mark_line(const YAML::Node& node);
/// " (did you mean '<prefix><candidate>'?)" for the candidate closest to `word` (edit distance
/// with transpositions, ignoring case, within a third of the length), or "".
std::string suggestion(const std::string& word, const std::vector<std::string>& candidates,
                       const std::string& prefix = "");

/// Most nodes a document may hold once its aliases are expanded (nested aliases can make a few
/// lines stand for billions of nodes). Far above any real scene: three axes of 100000 grid lines.
constexpr std::size_t kMaxDocumentNodes = 1000000;

/// True when `node`, its aliases expanded, holds more than `limit` nodes; then `where` is the key
/// path (below `path`, at most three keys deep) of the entry that crosses the limit and `line` its
/// line (or -1). Stops walking at the limit, so it costs at most `limit` steps.
bool exceeds_node_limit(const YAML::Node& node, std::size_t limit, const std::string& path, std::string& where,
                        int& line);

/// Nodes of `node` with its aliases expanded, counted up to `limit` + 1.
std::size_t count_nodes(const YAML::Node& node, std::size_t limit);

/// One step of a key path: a key, or an index into a list when `key` is empty.
struct PathStep {
  std::string key;
  std::size_t index = 0;
  std::string path;  ///< the path up to and including this step
};

/// Splits "transient.probes[0].point" into steps (transient, probes, [0], point); false if the
/// text is not a key path (keys of letters, digits, _ - +, indices in brackets, dots between).
bool split_path(const std::string& path, std::vector<PathStep>& steps);

}  // namespace crackle::scene

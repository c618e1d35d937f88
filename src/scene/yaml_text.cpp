/// \file Reading and describing YAML scalars for messages, shared by the scene validator and the
/// study plan (yaml_text.hpp).
#include "scene/yaml_text.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <set>
#include <vector>

#include "core/errors.hpp"

namespace crackle::scene {

bool parse_number(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && errno == 0 && std::isfinite(value);
}

bool parse_integer(const std::string& text, long long& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtoll(text.c_str(), &end, 10);
  return end == text.c_str() + text.size() && errno == 0;
}

bool is_quoted(const YAML::Node& node) { return node.Tag() == "!"; }

namespace {

/// YAML words that are not text: booleans, null, special floats. Messages show them unquoted.
bool is_yaml_word(const std::string& text) {
  static const std::set<std::string> words = {"true",  "false", "null", "~",   ".nan", ".inf",
                                              "-.inf", "+.inf", "nan",  "inf", "-inf", "+inf"};
  std::string lower = text;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  return words.count(lower) > 0;
}

}  // namespace

std::string describe_node(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsSequence()) {
    if (node.size() == 0) return "an empty list";
    return "a list of " + std::to_string(node.size()) + (node.size() == 1 ? " entry" : " entries");
  }
  if (node.IsMap()) return node.size() == 0 ? "an empty map" : "a map";
  const std::string& text = node.Scalar();
  double value = 0;
  if (!is_quoted(node) && parse_number(text, value)) return format_number(value);
  if (!is_quoted(node) && is_yaml_word(text)) return text;
  return "'" + text + "'";
}

int mark_line(const YAML::Node& node) {
  const int line = node.Mark().line;
  return line >= 0 ? line + 1 : -1;
}

namespace {

/// Edit distance with transpositions (optimal string alignment), ignoring case.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  auto same = [](char x, char y) {
    return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
  };
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = same(a[i - 1], b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && same(a[i - 1], b[j - 2]) && same(a[i - 2], b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

}  // namespace

std::string suggestion(const std::string& word, const std::vector<std::string>& candidates,
                       const std::string& prefix) {
  std::string best;
  std::size_t best_distance = std::string::npos;
  for (const std::string& candidate : candidates) {
    const std::size_t distance = edit_distance(word, candidate);
    const std::size_t allowed = std::max(word.size(), candidate.size()) / 3;
    if (distance <= allowed && distance < best_distance) {
      best = candidate;
      best_distance = distance;
    }
  }
  return best.empty() ? "" : " (did you mean '" + prefix + best + "'?)";
}

namespace {

/// Counts the nodes below `node` into `count`; true once the count passes `limit`, with
/// `where`/`line` the key path and line of the entry (at most three keys deep) that crossed it.
/// `path` and `key_line` are those of `node`'s entry.
bool count_nodes(const YAML::Node& node, std::size_t limit, std::size_t& count, const std::string& path,
                 int key_line, int depth, std::string& where, int& line) {
  if (++count > limit) {
    where = path;
    line = key_line;
    return true;
  }
  const bool deeper = depth < 3;
  if (node.IsMap()) {
    for (const auto& entry : node) {
      const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : "?";
      const std::string child = !deeper ? path : path.empty() ? key : path + "." + key;
      const int child_line = deeper ? mark_line(entry.first) : key_line;
      if (count_nodes(entry.first, limit, count, child, child_line, depth + 1, where, line) ||
          count_nodes(entry.second, limit, count, child, child_line, depth + 1, where, line))
        return true;
    }
  } else if (node.IsSequence()) {
    std::size_t index = 0;
    for (const auto& item : node) {
      const std::string child = deeper ? path + "[" + std::to_string(index) + "]" : path;
      if (count_nodes(item, limit, count, child, key_line, depth + 1, where, line)) return true;
      ++index;
    }
  }
  return false;
}

}  // namespace

bool exceeds_node_limit(const YAML::Node& node, std::size_t limit, const std::string& path, std::string& where,
                        int& line) {
  std::size_t count = 0;
  line = -1;
  return count_nodes(node, limit, count, path, mark_line(node), 0, where, line);
}

std::size_t count_nodes(const YAML::Node& node, std::size_t limit) {
  std::size_t count = 0;
  std::string where;
  int line = -1;
  count_nodes(node, limit, count, "", -1, 0, where, line);
  return count;
}

bool split_path(const std::string& path, std::vector<PathStep>& steps) {
  std::size_t i = 0;
  while (i < path.size()) {
    const std::size_t start = i;
    while (i < path.size() && (std::isalnum(static_cast<unsigned char>(path[i])) || path[i] == '_' ||
                               path[i] == '-' || path[i] == '+'))
      ++i;
    if (i == start) return false;
    steps.push_back({path.substr(start, i - start), 0, path.substr(0, i)});
    while (i < path.size() && path[i] == '[') {
      const std::size_t close = path.find(']', i);
      if (close == std::string::npos || close == i + 1) return false;
      const std::string digits = path.substr(i + 1, close - i - 1);
      if (!std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c); }))
        return false;
      i = close + 1;
      steps.push_back({"", std::stoul(digits), path.substr(0, i)});
    }
    if (i < path.size() && (path[i] != '.' || i + 1 == path.size())) return false;
    if (i < path.size()) ++i;
  }
  return !steps.empty();
}

}  // namespace crackle::scene

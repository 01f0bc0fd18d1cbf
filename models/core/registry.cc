// "Did you mean": the names a user most likely meant (registry.h).
#include "models/core/registry.h"

#include <cstddef>
#include <utility>

namespace springlab {
namespace {

// The name as compared: lower case, '_' and ' ' as '-'.
std::string folded(std::string_view name) {
  std::string out;
  for (char c : name) {
    const auto u = static_cast<unsigned char>(c);
    out += (c == '_' || c == ' ') ? '-' : static_cast<char>(std::tolower(u));
  }
  return out;
}

// The optimal string alignment distance (Damerau-Levenshtein without
// substrings edited twice): insertions, deletions, substitutions and swaps
// of two neighbours, each costing 1.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[n][m];
}

}  // namespace

std::vector<std::string> closest_names(std::string_view typed,
                                       const std::vector<std::string>& candidates) {
  constexpr std::size_t kLongest = 200;  // a pasted file is no name
  if (typed.empty() || typed.size() > kLongest) return {};
  const std::string t = folded(typed);
  std::vector<std::pair<std::size_t, std::string>> scored;
  for (const std::string& c : candidates) {
    const std::string f = folded(c);
    std::size_t distance = edit_distance(t, f);
    // One name the start of the other ("implicit" for "implicit-euler").
    if (f.size() > t.size() && t.size() >= 4 && f.compare(0, t.size(), t) == 0) distance = 1;
    const std::size_t allowed = std::max<std::size_t>(1, std::max(t.size(), f.size()) / 3);
    if (distance <= allowed) scored.emplace_back(distance, c);
  }
  std::stable_sort(scored.begin(), scored.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::string> out;
  // A name equal but for case or separators is the one meant: no others.
  const std::size_t slack = !scored.empty() && scored.front().first == 0 ? 0 : 1;
  for (const auto& [distance, name] : scored) {
    if (out.size() == 3 || distance > scored.front().first + slack) break;
    out.push_back(name);
  }
  return out;
}

std::string did_you_mean(std::string_view typed, const std::vector<std::string>& candidates) {
  const std::vector<std::string> close = closest_names(typed, candidates);
  if (close.empty()) return "";
  std::string text = " (did you mean ";
  for (std::size_t i = 0; i < close.size(); ++i) {
    if (i > 0) text += i + 1 == close.size() ? " or " : ", ";
    text += "'" + close[i] + "'";
  }
  return text + "?)";
}

}  // namespace springlab

// One strict reader of JSON text for scene files (models/model/scene_file.cc) and experiment
// definitions (experiments/kinds/experiment.cc). The JSON grammar (RFC 8259) lets an
// object hold a key twice and leaves the meaning open; nlohmann's parser would
// keep the last value silently. This reader refuses it, naming the object:
// "cases[0].scene: duplicate key 'name'".
//
// What differs between the two callers is a small policy: how a failure is
// reported (a callback that throws) and, for scene files, the resource caps.
// Paths are written the same way for both: "springs[3]", "wind.gust".
#pragma once

#include <cstddef>
#include <functional>
#include <limits>
#include <optional>
#include <string>

namespace springlab {

// Caps checked while the document grows, so that memory stays bounded
// whatever the file holds.
struct StrictJsonCaps {
  std::size_t max_nesting = std::numeric_limits<std::size_t>::max();  // open containers
  std::size_t max_values = std::numeric_limits<std::size_t>::max();   // values in the file
  // The most elements an array that is a value of the top-level object may
  // hold, by its key ("particles" -> 10^6); unset: no cap.
  std::function<std::size_t(const std::string& key)> top_level_array_cap;
  // The document's kind in messages: "over the cap for a <kind> file",
  // "over the cap of 100 per <kind>".
  std::string kind = "scene";
};

struct StrictJsonPolicy {
  // Reports a problem at `path` ("" for none) and throws; the reader never
  // continues after it.
  std::function<void(const std::string& path, const std::string& message)> fail;
  // A number beyond a double (1e999): "PATH: must be a finite number" when
  // true, else the library's "malformed JSON: number overflow ..." message.
  bool name_overflowing_number = false;
  std::optional<StrictJsonCaps> caps;  // none: only the library's limits
};

// Parses `text` into JsonT (nlohmann::json or nlohmann::ordered_json). An
// ordered_json object's keys also go in a hash set and are appended without
// a search, so an object of 10^5 keys is read in linear time. Every failure
// goes through policy.fail.
template <class JsonT>
JsonT parse_strict_json(const std::string& text, const StrictJsonPolicy& policy);

}  // namespace springlab

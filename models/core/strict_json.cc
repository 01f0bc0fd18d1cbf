// The strict JSON reader (strict_json.h): nlohmann's SAX interface drives a
// builder that tracks where it is in the document.
//
// nlohmann's callback parser could refuse duplicate keys too, but it rescans
// the parent array after every object: quadratic. Here an ordered_json
// object's keys are looked up in a hash set and appended without a search
// (ordered_json searches linearly, which made an object of 10^5 keys take a
// minute), and a path is built only for a message, from the open containers,
// so deep nesting costs memory in proportion to the depth (a frame is a
// pointer and a key).
#include "models/core/strict_json.h"

#include <algorithm>
#include <stdexcept>
#include <type_traits>
#include <unordered_set>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "models/core/scene.h"     // printable
#include "models/core/scene_io.h"  // field, element

namespace springlab {
namespace {

[[noreturn]] void report(const StrictJsonPolicy& policy, const std::string& path,
                         const std::string& message) {
  policy.fail(path, message);
  throw std::logic_error("StrictJsonPolicy::fail returned");  // it must throw
}

template <class JsonT>
class StrictJsonBuilder {
 public:
  StrictJsonBuilder(JsonT& root, const StrictJsonPolicy& policy) : root_(root), policy_(policy) {}

  bool null() { return add(nullptr); }
  bool boolean(bool value) { return add(value); }
  bool number_integer(typename JsonT::number_integer_t value) { return add(value); }
  bool number_unsigned(typename JsonT::number_unsigned_t value) { return add(value); }
  bool number_float(typename JsonT::number_float_t value, const std::string&) { return add(value); }
  bool string(std::string& value) { return add(std::move(value)); }
  bool binary(typename JsonT::binary_t& value) { return add(JsonT::binary(std::move(value))); }

  bool start_object(std::size_t) { return open(JsonT::object()); }
  bool start_array(std::size_t) { return open(JsonT::array()); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }

  bool key(std::string& key) {
    Frame& top = frames_.back();
    bool repeated;
    if constexpr (kAppends) {
      repeated = !top.keys.insert(key).second;
    } else {
      repeated = top.container->contains(key);
    }
    if (repeated)
      fail(container_path(frames_.size() - 1), "duplicate key '" + printable(key) + "'");
    top.key = std::move(key);
    return true;
  }

  bool parse_error(std::size_t, const std::string&, const nlohmann::json::exception& e) {
    // out_of_range 406: a number beyond a double (1e999), refused by the
    // library before the builder sees it.
    if (e.id == 406 && policy_.name_overflowing_number)
      fail(next_path().empty() ? "top level" : next_path(), "must be a finite number");
    std::string message = e.what();
    const auto bracket = message.find("] ");  // drop "[json.exception.parse_error.101] "
    if (message.rfind("[json.exception.", 0) == 0 && bracket != std::string::npos) {
      message.erase(0, bracket + 2);
    }
    std::replace(message.begin(), message.end(), '\n', ' ');
    report(policy_, "", "malformed JSON: " + message);
  }

 private:
  // ordered_json keeps an object as a vector searched linearly: its keys
  // also go in a hash set. nlohmann::json keeps a std::map, searched in
  // O(log n) already.
  static constexpr bool kAppends =
      requires(typename JsonT::object_t& object, std::string key, JsonT value) {
        object.emplace_back(key, std::move(value));
      };

  struct NoKeys {};
  using KeySet = std::conditional_t<kAppends, std::unordered_set<std::string>, NoKeys>;

  // One per open container: a file of n nested arrays keeps n frames, so a
  // frame holds no more than it needs (no path, no key set for a std::map).
  struct Frame {
    JsonT* container;
    std::string key;                         // objects: the key of the value being read
    [[no_unique_address]] KeySet keys = {};  // ordered_json objects: the keys read so far
  };

  [[noreturn]] void fail(const std::string& path, const std::string& message) const {
    report(policy_, path, message);
  }

  // The path of the open container frames_[depth]: each parent names its
  // open child by the key being read or by its last element's index.
  // Written as field() and element() write it ("cases[0].scene"), appended
  // in place: a path through 10^5 levels is built in linear time.
  std::string container_path(std::size_t depth) const {
    std::string path;
    for (std::size_t k = 1; k <= depth; ++k) {
      const Frame& parent = frames_[k - 1];
      if (parent.container->is_array()) {
        path += '[';
        path += std::to_string(parent.container->size() - 1);
        path += ']';
      } else {
        if (!path.empty()) path += '.';
        path += parent.key;
      }
    }
    return path;
  }

  // The path of the value being read now.
  std::string next_path() const {
    if (frames_.empty()) return "";
    const Frame& top = frames_.back();
    const std::string path = container_path(frames_.size() - 1);
    return top.container->is_array() ? element(path, top.container->size()) : field(path, top.key);
  }

  // Only the innermost open container grows, so pointers to the open ones
  // (each the last element of its parent) stay valid.
  JsonT* insert(JsonT&& value) {
    if (policy_.caps && ++values_ > policy_.caps->max_values) {
      fail(next_path().empty() ? "top level" : next_path(),
           "the file holds more than " + std::to_string(policy_.caps->max_values) +
               " JSON values, over the cap for a " + policy_.caps->kind + " file");
    }
    if (frames_.empty()) {
      root_ = std::move(value);
      return &root_;
    }
    Frame& frame = frames_.back();
    JsonT& top = *frame.container;
    if (top.is_array()) {
      if (frames_.size() == 2 && top.size() >= top_level_array_cap_) {
        const std::string path = container_path(1);
        fail(path, "more than " + std::to_string(top_level_array_cap_) + " " + path +
                       ", over the cap of " + std::to_string(top_level_array_cap_) + " per " +
                       policy_.caps->kind);
      }
      top.push_back(std::move(value));
      return &top.back();
    }
    // key() has refused a duplicate, so the key is new: append, no search
    // (ordered_json keeps a vector; nlohmann::json a std::map).
    auto& object = top.template get_ref<typename JsonT::object_t&>();
    if constexpr (kAppends) {
      object.emplace_back(frame.key, std::move(value));
      return &object.back().second;
    } else {
      return &object.emplace(frame.key, std::move(value)).first->second;
    }
  }

  bool add(JsonT&& value) {
    insert(std::move(value));
    return true;
  }

  bool open(JsonT&& container) {
    if (policy_.caps && frames_.size() >= policy_.caps->max_nesting) {
      fail(next_path(), "nested deeper than " + std::to_string(policy_.caps->max_nesting) +
                            " levels, over the cap for a " + policy_.caps->kind + " file");
    }
    // A top-level array (the parent is the root object) may have a cap.
    const bool top_level_array = frames_.size() == 1 && container.is_array() &&
                                 frames_.back().container->is_object();
    if (frames_.size() == 1) {
      top_level_array_cap_ = std::numeric_limits<std::size_t>::max();
      if (top_level_array && policy_.caps && policy_.caps->top_level_array_cap)
        top_level_array_cap_ = policy_.caps->top_level_array_cap(frames_.back().key);
    }
    frames_.push_back({insert(std::move(container)), {}});
    return true;
  }

  bool close() {
    frames_.pop_back();
    return true;
  }

  JsonT& root_;
  const StrictJsonPolicy& policy_;
  std::vector<Frame> frames_;
  std::size_t values_ = 0;
  // The cap on the open container frames_[1] when it is a top-level array.
  std::size_t top_level_array_cap_ = std::numeric_limits<std::size_t>::max();
};

}  // namespace

template <class JsonT>
JsonT parse_strict_json(const std::string& text, const StrictJsonPolicy& policy) {
  JsonT document;
  StrictJsonBuilder<JsonT> builder(document, policy);
  JsonT::sax_parse(text, &builder);  // every failure throws from the builder
  return document;
}

template nlohmann::json parse_strict_json<nlohmann::json>(const std::string&,
                                                          const StrictJsonPolicy&);
template nlohmann::ordered_json parse_strict_json<nlohmann::ordered_json>(
    const std::string&, const StrictJsonPolicy&);

}  // namespace springlab

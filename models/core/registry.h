// One way to register things by name, for every registry of springlab
// (integrators, materials, element kinds, experiment kinds, built-in
// scenes): each entry is defined in its own file by a function that returns
// its descriptor, `const Entry& accessor()`; the registry's file lists
// them, one line each, in an X-macro, and SPRINGLAB_REGISTRY declares the
// functions and keeps them in that order:
//
//   #define SPRINGLAB_MATERIALS(X)
//     X(MaterialModel, linear_material)
//     X(MaterialModel, stvk_material)  ...
//   SPRINGLAB_REGISTRY(MaterialModel, SPRINGLAB_MATERIALS, material_registry)
//
// declares `const MaterialModel& stvk_material();` (defined in stvk.cc) and
// defines `Registry<MaterialModel>& material_registry()`. Adding an entry
// is its file and one line in the list. Entries may also be added while
// the program runs (a plug-in's integrators, docs/your-own-integrator.md):
// Registry::add. An Entry has a `name` (anything std::string_view takes).
#pragma once

#include <algorithm>
#include <cctype>
#include <initializer_list>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace springlab {

// The names among `candidates` a user who typed `typed` most likely meant
// (closest first, at most three): equal but for case, '-' against '_' or ' ',
// or within an edit distance of about a third of the name (Damerau-
// Levenshtein: insert, delete, substitute, swap two neighbours). Empty when
// none is close.
std::vector<std::string> closest_names(std::string_view typed,
                                       const std::vector<std::string>& candidates);

// " (did you mean 'a' or 'b'?)" for closest_names, or "" when none.
std::string did_you_mean(std::string_view typed, const std::vector<std::string>& candidates);

template <class Entry>
class Registry {
 public:
  using Source = const Entry& (*)();

  Registry(std::initializer_list<Source> built_in) {
    for (Source source : built_in) entries_.push_back(&source());
  }

  // Every entry, built-ins in the registry file's order, then those added.
  std::vector<const Entry*> entries() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return entries_;
  }

  // The entry of that name, or nullptr.
  const Entry* find(std::string_view name) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const Entry* e : entries_) {
      if (std::string_view(e->name) == name) return e;
    }
    return nullptr;
  }

  // The names, in registry order.
  std::vector<std::string> names() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> out;
    for (const Entry* e : entries_) out.emplace_back(e->name);
    return out;
  }

  // Adds an entry at run time (it must outlive the registry's use: a
  // static of the caller). Throws std::invalid_argument when the name is
  // taken or empty.
  void add(const Entry& entry) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string_view name(entry.name);
    if (name.empty()) throw std::invalid_argument("an entry needs a name");
    for (const Entry* e : entries_) {
      if (std::string_view(e->name) == name) {
        throw std::invalid_argument("'" + std::string(name) + "' is already registered");
      }
    }
    entries_.push_back(&entry);
  }

  // "unknown WHAT 'NAME' (did you mean 'X'?) (WHATs: a, b, c)": the
  // message for a name that is not here, with the names sorted.
  std::string unknown(std::string_view what, std::string_view name) const {
    std::vector<std::string> all = names();
    std::string text = "unknown " + std::string(what) + " '" + std::string(name) + "'" +
                       did_you_mean(name, all);
    std::sort(all.begin(), all.end());
    std::string list;
    for (const std::string& n : all) list += (list.empty() ? "" : ", ") + n;
    return text + " (" + std::string(what) + "s: " + list + ")";
  }

 private:
  mutable std::mutex mutex_;
  std::vector<const Entry*> entries_;
};

}  // namespace springlab

// The registry of a list of entries, one line X(ENTRY, accessor) each:
// declares `const ENTRY& accessor();` for each (defined in the entry's own
// file) and defines `Registry<ENTRY>& FUNCTION()` holding them in list
// order. Used in each registry's file, inside namespace springlab.
#define SPRINGLAB_REGISTRY_DECLARE(ENTRY, ACCESSOR) const ENTRY& ACCESSOR();
#define SPRINGLAB_REGISTRY_SOURCE(ENTRY, ACCESSOR) &ACCESSOR,
#define SPRINGLAB_REGISTRY(ENTRY, LIST, FUNCTION)                  \
  LIST(SPRINGLAB_REGISTRY_DECLARE)                                 \
  Registry<ENTRY>& FUNCTION() {                                    \
    static Registry<ENTRY> registry = {LIST(SPRINGLAB_REGISTRY_SOURCE)}; \
    return registry;                                               \
  }

// The strict JSON reader (models/core/strict_json.h) shared by scene files and
// experiment definitions: it reads what nlohmann's parser reads, refuses a
// duplicate key naming the object, and enforces the optional caps with the
// path of the value that goes over them.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "models/core/strict_json.h"

namespace springlab::test_strict_json {
namespace {

// A failure as the policy's callback saw it.
struct Refusal {
  std::string path;
  std::string message;
};

StrictJsonPolicy recording_policy() {
  StrictJsonPolicy policy;
  policy.fail = [](const std::string& path, const std::string& message) {
    throw Refusal{path, message};
  };
  return policy;
}

template <class JsonT>
Refusal refusal(const std::string& text, const StrictJsonPolicy& policy) {
  try {
    parse_strict_json<JsonT>(text, policy);
  } catch (const Refusal& r) {
    return r;
  }
  ADD_FAILURE() << "accepted: " << text;
  return {};
}

const std::string kDocument =
    R"({"zeta": [1, -2, 3.5, true, null, "s"], "alpha": {"b": [[], {}], "a": 18446744073709551615}})";

TEST(StrictJson, ReadsWhatTheLibraryReadsForBothKeyOrders) {
  const StrictJsonPolicy policy = recording_policy();
  const auto ordered = parse_strict_json<nlohmann::ordered_json>(kDocument, policy);
  const auto sorted = parse_strict_json<nlohmann::json>(kDocument, policy);
  EXPECT_EQ(ordered, nlohmann::ordered_json::parse(kDocument));
  EXPECT_EQ(sorted, nlohmann::json::parse(kDocument));
  // ordered_json keeps the file's key order; json sorts the keys.
  EXPECT_EQ(ordered.dump(), nlohmann::ordered_json::parse(kDocument).dump());
  EXPECT_EQ(ordered.begin().key(), "zeta");
  EXPECT_EQ(sorted.begin().key(), "alpha");
}

TEST(StrictJson, DuplicateKeyNamesTheObjectInBothKeyOrders) {
  const std::string text = R"({"cases": [{"x": 1}, {"scene": {"n": 1, "m": 2, "n": 3}}]})";
  for (const Refusal& r : {refusal<nlohmann::json>(text, recording_policy()),
                           refusal<nlohmann::ordered_json>(text, recording_policy())}) {
    EXPECT_EQ(r.path, "cases[1].scene");
    EXPECT_EQ(r.message, "duplicate key 'n'");
  }
  const Refusal top = refusal<nlohmann::json>(R"({"a": 1, "a": 1})", recording_policy());
  EXPECT_EQ(top.path, "");
  EXPECT_EQ(top.message, "duplicate key 'a'");
}

TEST(StrictJson, OverflowingNumberIsNamedOnlyWhenThePolicyAsks) {
  StrictJsonPolicy policy = recording_policy();
  const std::string text = R"({"wind": {"velocity": [0, 1e999]}})";
  const Refusal plain = refusal<nlohmann::json>(text, policy);
  EXPECT_EQ(plain.path, "");
  EXPECT_EQ(plain.message.rfind("malformed JSON: ", 0), 0u) << plain.message;
  policy.name_overflowing_number = true;
  const Refusal named = refusal<nlohmann::json>(text, policy);
  EXPECT_EQ(named.path, "wind.velocity[1]");
  EXPECT_EQ(named.message, "must be a finite number");
  EXPECT_EQ(refusal<nlohmann::json>("1e999", policy).path, "top level");
}

TEST(StrictJson, CapsNameTheValueThatGoesOver) {
  StrictJsonPolicy policy = recording_policy();
  StrictJsonCaps caps;
  caps.max_nesting = 3;
  caps.max_values = 8;
  caps.top_level_array_cap = [](const std::string& key) { return key == "xs" ? 2 : 100; };
  caps.kind = "test";
  policy.caps = caps;

  EXPECT_NO_THROW(parse_strict_json<nlohmann::json>(R"({"a": [[1]]})", policy));
  const Refusal deep = refusal<nlohmann::json>(R"({"a": [[{"b": 1}]]})", policy);
  EXPECT_EQ(deep.path, "a[0][0]");
  EXPECT_EQ(deep.message, "nested deeper than 3 levels, over the cap for a test file");

  EXPECT_NO_THROW(parse_strict_json<nlohmann::json>(R"({"xs": [1, 2], "ys": [1, 2, 3]})", policy));
  // Only an array that is a value of the top-level object is capped.
  EXPECT_NO_THROW(parse_strict_json<nlohmann::json>(R"({"w": {"xs": [1, 2, 3]}})", policy));
  EXPECT_NO_THROW(parse_strict_json<nlohmann::json>(R"([[1, 2, 3]])", policy));
  const Refusal long_array = refusal<nlohmann::json>(R"({"xs": [1, 2, 3]})", policy);
  EXPECT_EQ(long_array.path, "xs");
  EXPECT_EQ(long_array.message, "more than 2 xs, over the cap of 2 per test");

  // 8 values pass (the object, the array and 6 numbers); the 9th is named.
  EXPECT_NO_THROW(parse_strict_json<nlohmann::json>(R"({"ys": [1, 2, 3, 4, 5, 6]})", policy));
  const Refusal many = refusal<nlohmann::json>(R"({"ys": [1, 2, 3, 4, 5, 6, 7]})", policy);
  EXPECT_EQ(many.path, "ys[6]");
  EXPECT_EQ(many.message, "the file holds more than 8 JSON values, over the cap for a test file");
}

// Without caps (definitions), nesting is bounded only by the text; the path
// of a deep duplicate is still exact: one "[0]" per enclosing array.
TEST(StrictJson, DeepDuplicateKeyWithoutCapsHasTheFullPath) {
  const std::size_t depth = 5000;
  const std::string text =
      std::string(depth, '[') + R"({"k": 1, "k": 2})" + std::string(depth, ']');
  const Refusal r = refusal<nlohmann::json>(text, recording_policy());
  std::string expected;
  for (std::size_t i = 0; i < depth; ++i) expected += "[0]";
  EXPECT_EQ(r.path, expected);
  EXPECT_EQ(r.message, "duplicate key 'k'");
}

TEST(StrictJson, PolicyThatDoesNotThrowIsALogicError) {
  StrictJsonPolicy policy;
  policy.fail = [](const std::string&, const std::string&) {};
  EXPECT_THROW(parse_strict_json<nlohmann::json>(R"({"a": 1, "a": 2})", policy), std::logic_error);
}

}  // namespace
}  // namespace springlab::test_strict_json

// Structure-aware libFuzzer target for model files (FLATSOS_FUZZ=ON, clang; see CMakeLists.txt
// here). Its mutator keeps the input valid JSON and changes one to three values the way a
// careless or hostile author would: a number made zero, negative, huge, tiny or a NaN-like
// string; a string made empty, very long, or another name of the file (duplicate names, a body
// its own parent, cycles); an array shortened, lengthened or emptied (wrong sizes); a key removed,
// nulled or unknown. The byte fuzzer (fuzz_model_loader) rarely gets past the JSON parser; this
// one reaches the checks behind it. What model_check.hpp allows, nothing else.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "model_check.hpp"

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

namespace {

using nlohmann::json;
using Random = std::mt19937;

std::size_t pick(Random& random, std::size_t count) {
  return std::uniform_int_distribution<std::size_t>(0, count - 1)(random);
}

void collect(json& value, std::vector<json*>& values, std::vector<std::string>& strings) {
  values.push_back(&value);
  if (value.is_string()) strings.push_back(value.get<std::string>());
  if (value.is_structured())
    for (auto& child : value) collect(child, values, strings);
}

json hostile_number(Random& random, double x) {
  const json choices[] = {0,       -x,      -1,   x * 1e6,      1e308,      -1e308,
                          1e-308,  5e-324,  1e19, "NaN",        "Infinity", "-inf",
                          "1e999", nullptr, true, json::array()};
  return choices[pick(random, std::size(choices))];
}

json hostile_string(Random& random, const std::vector<std::string>& strings) {
  switch (pick(random, 4)) {
    case 0:
      return "";
    case 1:
      return std::string(300, 'x');
    case 2:
      return 0;
    default:
      return strings[pick(random, strings.size())];  // a name of the file: duplicates, cycles
  }
}

void mutate_array(Random& random, json& array) {
  if (array.empty()) {
    array.push_back(0);
    return;
  }
  switch (pick(random, 4)) {
    case 0:
      array.erase(array.begin() + static_cast<std::ptrdiff_t>(pick(random, array.size())));
      break;
    case 1:
      array.push_back(array[pick(random, array.size())]);
      break;  // one too many, or a duplicate
    case 2:
      array = json::array();
      break;
    default:
      array = array[0];
      break;  // a scalar or an object where a list was
  }
}

void mutate_object(Random& random, json& object) {
  if (object.empty()) {
    object["unknown_key"] = 1;
    return;
  }
  auto key = object.begin();
  std::advance(key, static_cast<std::ptrdiff_t>(pick(random, object.size())));
  switch (pick(random, 4)) {
    case 0:
      object.erase(key);
      break;
    case 1:
      key.value() = nullptr;
      break;
    case 2:
      object["unknown_key"] = key.value();
      break;
    default:
      object = json::array({object});
      break;
  }
}

void mutate_once(Random& random, json& document) {
  std::vector<json*> values;
  std::vector<std::string> strings{"ground"};
  collect(document, values, strings);
  json& value = *values[pick(random, values.size())];
  if (value.is_number())
    value = hostile_number(random, value.get<double>());
  else if (value.is_string())
    value = hostile_string(random, strings);
  else if (value.is_array())
    mutate_array(random, value);
  else if (value.is_object())
    mutate_object(random, value);
  else
    value = hostile_number(random, 1.0);
}

}  // namespace

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size,
                                               std::size_t max_size, unsigned int seed) {
  json document = json::parse(data, data + size, nullptr, false);
  if (document.is_discarded() || !document.is_structured())
    return LLVMFuzzerMutate(data, size, max_size);
  Random random(seed);
  for (std::size_t k = 0, count = 1 + pick(random, 3); k < count; ++k)
    mutate_once(random, document);
  const std::string text = document.dump(1);
  if (text.size() > max_size) return LLVMFuzzerMutate(data, size, max_size);
  std::memcpy(data, text.data(), text.size());
  return text.size();
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  flatsos::fuzz::check_model_text(std::string(reinterpret_cast<const char*>(data), size));
  return 0;
}

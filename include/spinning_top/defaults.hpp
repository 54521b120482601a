// The defaults of the numeric configuration keys, from their one source, defaults.def: as
// constants (defaults::kMass, ...) for the structs' member initialisers, and as a key -> value
// table for the key table (config.cpp), which shows them as text.
#pragma once

namespace spinning_top {
namespace defaults {

#define SPINNING_TOP_DEFAULT(constant, key, value) inline constexpr double constant = value;
#include "spinning_top/defaults.def"
#undef SPINNING_TOP_DEFAULT

struct KeyDefault {
  const char* key;
  double value;
};

/// Every entry of defaults.def, in its order.
inline constexpr KeyDefault kByKey[] = {
#define SPINNING_TOP_DEFAULT(constant, key, value) {key, constant},
#include "spinning_top/defaults.def"
#undef SPINNING_TOP_DEFAULT
};

}  // namespace defaults
}  // namespace spinning_top

#include "mpmcd/grid/shape.hpp"

#include "mpmcd/core/errors.hpp"

namespace mpmcd::grid {

ShapeKind shape_kind_from_string(const std::string& name) {
  if (name == "linear") return ShapeKind::kLinear;
  if (name == "ugimp") return ShapeKind::kUGimp;
  throw InputError("", 0, "grid.shape_function",
                   "expected \"linear\" or \"ugimp\", got \"" + name + "\"");
}

}  // namespace mpmcd::grid

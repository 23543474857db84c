#include "mpmcd/grid/shape.hpp"

#include "mpmcd/core/errors.hpp"

namespace mpmcd::grid {

ShapeKind shape_kind_from_string(const std::string& name) {
  if (name == "linear") return ShapeKind::kLinear;
  if (name == "ugimp") return ShapeKind::kUGimp;
  if (name == "cpdi") return ShapeKind::kCpdi;
  throw InputError("", 0, "grid.shape_function",
                   "expected \"linear\", \"ugimp\" or \"cpdi\", got \"" + name + "\"");
}

}  // namespace mpmcd::grid

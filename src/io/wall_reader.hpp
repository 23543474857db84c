#pragma once
// The readers of [[walls]], [loading] and [stop] (private to src/io/, wall_reader.cpp), called by
// the input's reader (config_reader.cpp) after the tables they refer to.
#include <string>
#include <vector>

#include "mpmcd/io/config.hpp"
#include "mpmcd/io/schema.hpp"

namespace mpmcd::io {

/// Reads the walls and what refers to them, for an input of dimension `dim`.
struct WallReader {
  const std::string& source;  ///< the input's name, for messages
  std::size_t dim;            ///< simulation.dimension [-]

  /// [[walls]]: names (unique; letters, digits, '_', '-'), unit normals, velocity 0 by default.
  void read_walls(const TableReader& root, Config& c) const;
  /// [loading] and its stages: servo and moving walls naming [[walls]] entries, until conditions.
  void read_loading(const TableReader& root, Config& c) const;
  /// [stop]: criteria on phi, strain and stress need the walls to form a box.
  void read_stop(const TableReader& root, Config& c) const;

 private:
  /// The walls form a box: exactly 2 Dim, with normals +x, -x, +y, -y (and +z, -z in 3D;
  /// analysis::find_box).
  bool walls_form_box(const std::vector<WallSection>& walls) const;
  /// "four [[walls]] forming a box (normals +x, -x, +y, -y" (six and +-z in 3D), for messages.
  std::string box_words() const;
  /// The wall named `name` (its index), or an error at `key` of `r` naming the walls defined.
  template <class S, class M>
  static std::size_t wall_index(const TableReader& r, M S::*key, const std::string& name,
                                const Config& c);
};

}  // namespace mpmcd::io

#include "mpmcd/checkpoint/checkpoint.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/parallel/partition.hpp"
#include "mpmcd/version.hpp"

namespace mpmcd::checkpoint {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kUserBlock = kHeaderBytes;  // before the HDF5 superblock (power of 2 >= 512)
static_assert(kUserBlock >= 512 && (kUserBlock & (kUserBlock - 1)) == 0);
constexpr std::string_view kMagic = "MPMCD-CHECKPOINT";

// ---------------------------------------------------------------------------------------------
// RAII handles of the HDF5 C API.
class Handle {
 public:
  Handle() = default;
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = H5I_INVALID_HID; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      close_ = o.close_;
      o.id_ = H5I_INVALID_HID;
    }
    return *this;
  }
  // Closes the object now; false if the library reports an error.
  bool reset() {
    const bool ok = id_ < 0 || !close_ || close_(id_) >= 0;
    id_ = H5I_INVALID_HID;
    return ok;
  }
  ~Handle() { reset(); }
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_ = H5I_INVALID_HID;
  herr_t (*close_)(hid_t) = nullptr;
};

// HDF5 prints its error stack by default; errors are reported through exceptions instead.
void quiet_hdf5() {
  static const bool done = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)done;
}

template <class T>
struct H5Type;
template <>
struct H5Type<double> {
  static hid_t mem() { return H5T_NATIVE_DOUBLE; }
  static hid_t file() { return H5T_IEEE_F64LE; }
  static constexpr H5T_class_t cls = H5T_FLOAT;
};
template <>
struct H5Type<std::int64_t> {
  static hid_t mem() { return H5T_NATIVE_INT64; }
  static hid_t file() { return H5T_STD_I64LE; }
  static constexpr H5T_class_t cls = H5T_INTEGER;
};
template <>
struct H5Type<std::int32_t> {
  static hid_t mem() { return H5T_NATIVE_INT32; }
  static hid_t file() { return H5T_STD_I32LE; }
  static constexpr H5T_class_t cls = H5T_INTEGER;
};
template <>
struct H5Type<std::uint64_t> {
  static hid_t mem() { return H5T_NATIVE_UINT64; }
  static hid_t file() { return H5T_STD_U64LE; }
  static constexpr H5T_class_t cls = H5T_INTEGER;
};
template <>
struct H5Type<unsigned char> {
  static hid_t mem() { return H5T_NATIVE_UCHAR; }
  static hid_t file() { return H5T_STD_U8LE; }
  static constexpr H5T_class_t cls = H5T_INTEGER;
};

// ---------------------------------------------------------------------------------------------
// Writing.
class Writer {
 public:
  explicit Writer(const std::string& path) : path_(path) {
    Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
    if (!fcpl.ok() || H5Pset_userblock(fcpl.get(), kUserBlock) < 0) fail("file properties");
    file_ = Handle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), H5P_DEFAULT), H5Fclose);
    if (!file_.ok()) fail("create");
  }
  void group(const char* name) {
    Handle gcpl(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
    H5Pset_obj_track_times(gcpl.get(), false);  // no timestamps: same state, same bytes
    Handle g(H5Gcreate2(file_.get(), name, H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose);
    if (!g.ok()) fail(name);
  }
  template <class T>
  void array(const std::string& name, const std::vector<T>& data, std::vector<hsize_t> dims) {
    hsize_t total = 1;
    for (hsize_t d : dims) total *= d;
    if (total != data.size()) fail(name + " (size)");
    Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
    Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_obj_track_times(dcpl.get(), false);
    Handle set(H5Dcreate2(file_.get(), name.c_str(), H5Type<T>::file(), space.get(), H5P_DEFAULT,
                          dcpl.get(), H5P_DEFAULT),
               H5Dclose);
    if (!space.ok() || !set.ok()) fail(name);
    if (!data.empty() &&
        H5Dwrite(set.get(), H5Type<T>::mem(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0)
      fail(name);
  }
  void text(const std::string& name, const std::string& s) {
    array(name, std::vector<unsigned char>(s.begin(), s.end()), {s.size()});
  }
  template <class T>
  void scalar(const std::string& name, T value) {
    array(name, std::vector<T>{value}, {1});
  }
  void close() {
    if (H5Fflush(file_.get(), H5F_SCOPE_GLOBAL) < 0 || !file_.reset()) fail("close");
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(fmt::format("cannot write checkpoint '{}' ({})", path_, what));
  }
  std::string path_;
  Handle file_;
};

// FNV-1a of the bytes of `f` from `offset` to the end, continuing from `h`.
std::uint64_t file_checksum(std::FILE* f, std::size_t offset, std::size_t& bytes, std::uint64_t h) {
  std::vector<char> buf(1 << 20);
  bytes = 0;
  if (std::fseek(f, static_cast<long>(offset), SEEK_SET) != 0) return 0;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), f)) > 0) {
    h = fnv1a(std::string_view(buf.data(), n), h);
    bytes += n;
  }
  return h;
}

// The header block: text padded with NUL bytes to kUserBlock.
std::string header_text(std::size_t bytes, std::uint64_t sum) {
  std::string h =
      fmt::format("{} {}\nbytes {}\nfnv1a64 {:016x}\n", kMagic, kFormatVersion, bytes, sum);
  h.resize(kUserBlock, '\0');
  return h;
}

constexpr std::string_view kSumKey = "\nfnv1a64 ";
constexpr std::size_t kSumDigits = 16;

void fsync_path(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags);
  if (fd < 0) return;
  (void)::fsync(fd);
  ::close(fd);
}

// ---------------------------------------------------------------------------------------------
// Reading.
class Reader {
 public:
  // `max_bytes`: the file size; no dataset can hold more (contiguous, uncompressed).
  Reader(const std::string& path, std::size_t max_bytes) : path_(path), max_bytes_(max_bytes) {
    file_ = Handle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (!file_.ok()) fail("", "not a readable HDF5 file");
  }
  template <class T>
  std::vector<T> array(const std::string& name, std::vector<hsize_t> dims) {
    if (H5Lexists(file_.get(), name.c_str(), H5P_DEFAULT) <= 0) fail(name, "dataset missing");
    Handle set(H5Dopen2(file_.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
    if (!set.ok()) fail(name, "not a dataset");
    Handle type(H5Dget_type(set.get()), H5Tclose);
    if (!type.ok() || H5Tget_class(type.get()) != H5Type<T>::cls ||
        H5Tget_size(type.get()) != sizeof(T))
      fail(name, "wrong element type");
    Handle space(H5Dget_space(set.get()), H5Sclose);
    const int rank = space.ok() ? H5Sget_simple_extent_ndims(space.get()) : -1;
    if (rank != static_cast<int>(dims.size())) fail(name, "wrong rank");
    std::vector<hsize_t> got(dims.size());
    if (!dims.empty()) H5Sget_simple_extent_dims(space.get(), got.data(), nullptr);
    hsize_t total = 1;
    for (std::size_t k = 0; k < dims.size(); ++k) {
      if (dims[k] == kAny) dims[k] = got[k];
      if (got[k] != dims[k])
        fail(name, fmt::format("dimension {} is {}, expected {}", k, got[k], dims[k]));
      total *= dims[k];
    }
    // Sizes come from the file: bound them by the file before allocating (fuzzing found a
    // re-sealed file declaring 2^32 entries).
    if (total > max_bytes_ / sizeof(T))
      fail(name, fmt::format("declares {} entries, more than the file can hold", total));
    if (total > 0 && H5Dget_storage_size(set.get()) < total * sizeof(T))
      fail(name, "its stored data is shorter than its size");
    std::vector<T> out(static_cast<std::size_t>(total));
    if (total > 0 &&
        H5Dread(set.get(), H5Type<T>::mem(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
      fail(name, "cannot be read");
    return out;
  }
  std::string text(const std::string& name) {
    const auto bytes = array<unsigned char>(name, {kAny});
    return std::string(bytes.begin(), bytes.end());
  }
  template <class T>
  T scalar(const std::string& name) {
    return array<T>(name, {1})[0];
  }
  [[noreturn]] void fail(const std::string& dataset, const std::string& what) const {
    throw InputError(path_, 0, dataset, "checkpoint refused: " + what);
  }
  static constexpr hsize_t kAny = ~hsize_t{0};

 private:
  std::string path_;
  std::size_t max_bytes_;
  Handle file_;
};

template <class T>
std::uint64_t hash_array(const std::vector<T>& a, std::uint64_t h) {
  const std::uint64_t n = a.size();
  h = fnv1a(std::string_view(reinterpret_cast<const char*>(&n), sizeof n), h);
  return fnv1a(std::string_view(reinterpret_cast<const char*>(a.data()), a.size() * sizeof(T)), h);
}

template <class T>
std::uint64_t hash_value(T v, std::uint64_t h) {
  return fnv1a(std::string_view(reinterpret_cast<const char*>(&v), sizeof v), h);
}

}  // namespace

std::uint64_t fnv1a(std::string_view bytes, std::uint64_t hash) {
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  return hash;
}

std::uint64_t payload_checksum(const State& s) {
  std::uint64_t h = kFnvOffset;
  h = fnv1a(s.input_text, h);
  for (auto v : {s.dim}) h = hash_value(v, h);
  for (auto v : {s.step, s.good_since_cut, s.failed_steps, s.newton_iterations, s.csv_rows})
    h = hash_value(v, h);
  for (auto v : {s.time, s.dt, s.next_vtu, s.next_csv, s.energy0, s.contact_dissipation, s.kinetic0,
                 s.transfer_dissipation, s.stress_work, s.body_work})
    h = hash_value(v, h);
  for (const auto* a : {&s.vtu_times, &s.x, &s.v, &s.L, &s.F, &s.sigma, &s.domain, &s.sigma_zz,
                        &s.mass, &s.volume0, &s.volume, &s.history, &s.grain_half_width,
                        &s.warm_impulse, &s.wall_point, &s.grain_work, &s.wall_work})
    h = hash_array(*a, h);
  for (const auto* a : {&s.grain, &s.grain_material, &s.warm_a, &s.warm_b, &s.grain_owner})
    h = hash_array(*a, h);
  // Version 7: the wall loading, hashed only when present (a state without it, such as every
  // version 6 file, keeps the checksum of version 6).
  if (!s.loading_stage.empty() || !s.loading_control.empty() || !s.loading_wall.empty()) {
    for (const auto* a : {&s.loading_stage, &s.loading_wall}) h = hash_array(*a, h);
    h = hash_array(s.loading_control, h);
  }
  h = hash_value(s.ranks, h);
  h = fnv1a(s.scheme, h);
  h = hash_value(s.threads, h);
  for (const auto* a : {&s.grain_begin, &s.grain_end, &s.grain_history_offset, &s.warm_node})
    h = hash_array(*a, h);
  return h;
}

void write(const State& s, const std::string& path) {
  quiet_hdf5();
  const std::string tmp = path + ".tmp";
  const hsize_t n = s.points(), d = static_cast<hsize_t>(s.dim);
  {
    Writer w(tmp);
    w.group("/meta");
    w.text("/meta/format", std::string(kMagic));
    w.scalar("/meta/format_version", kFormatVersion);
    w.text("/meta/mpmcd_version", fmt::format("{} ({})", kVersion, kGitHash));
    w.text("/meta/input_text", s.input_text);
    w.text("/meta/input_path", s.input_path);
    w.scalar("/meta/input_hash", fnv1a(s.input_text));
    w.text("/meta/reason", s.reason);
    w.scalar("/meta/payload_checksum", payload_checksum(s));
    w.scalar("/meta/dim", s.dim);
    w.group("/time");
    w.scalar("/time/step", s.step);
    w.scalar("/time/t", s.time);
    w.scalar("/time/dt", s.dt);
    w.scalar("/time/good_since_cut", s.good_since_cut);
    w.scalar("/time/failed_steps", s.failed_steps);
    w.scalar("/time/newton_iterations", s.newton_iterations);
    w.group("/output");
    w.scalar("/output/next_vtu", s.next_vtu);
    w.scalar("/output/next_csv", s.next_csv);
    w.scalar("/output/csv_rows", s.csv_rows);
    w.array("/output/vtu_times", s.vtu_times, {s.vtu_times.size()});
    w.group("/points");
    w.array("/points/x", s.x, {n, d});
    w.array("/points/v", s.v, {n, d});
    w.array("/points/L", s.L, {n, d, d});
    w.array("/points/F", s.F, {n, d, d});
    w.array("/points/sigma", s.sigma, {n, d, d});
    w.array("/points/domain", s.domain, {n, d, d});
    w.array("/points/sigma_zz", s.sigma_zz, {n});
    w.array("/points/mass", s.mass, {n});
    w.array("/points/volume0", s.volume0, {n});
    w.array("/points/volume", s.volume, {n});
    w.array("/points/grain", s.grain, {n});
    w.array("/points/history", s.history, {s.history.size()});
    const hsize_t ng = s.grain_begin.size();
    w.group("/grains");
    w.array("/grains/begin", s.grain_begin, {ng});
    w.array("/grains/end", s.grain_end, {ng});
    w.array("/grains/material", s.grain_material, {ng});
    w.array("/grains/half_width", s.grain_half_width, {ng});
    w.array("/grains/history_offset", s.grain_history_offset, {ng});
    const hsize_t nw = s.warm_node.size();
    w.group("/contact");
    w.array("/contact/warm_node", s.warm_node, {nw});
    w.array("/contact/warm_a", s.warm_a, {nw});
    w.array("/contact/warm_b", s.warm_b, {nw});
    w.array("/contact/warm_impulse", s.warm_impulse, {nw, d});
    w.group("/walls");
    w.array("/walls/point", s.wall_point, {s.wall_point.size() / std::max<hsize_t>(d, 1), d});
    w.array("/walls/work", s.wall_work, {s.wall_work.size()});
    w.group("/loading");
    w.array("/loading/stage", s.loading_stage, {s.loading_stage.size()});
    w.array("/loading/control", s.loading_control, {s.loading_control.size()});
    w.array("/loading/wall", s.loading_wall, {s.loading_wall.size()});
    w.scalar("/time/energy0", s.energy0);
    w.scalar("/time/contact_dissipation", s.contact_dissipation);
    w.scalar("/time/kinetic0", s.kinetic0);
    w.scalar("/time/transfer_dissipation", s.transfer_dissipation);
    w.scalar("/time/stress_work", s.stress_work);
    w.scalar("/time/body_work", s.body_work);
    w.group("/parallel");
    w.scalar("/parallel/ranks", s.ranks);
    w.text("/parallel/scheme", s.scheme);
    w.array("/parallel/grain_owner", s.grain_owner, {ng});
    w.array("/parallel/grain_work", s.grain_work, {ng, parallel::kWorkPhases});
    w.scalar("/parallel/threads", s.threads);
    w.close();
  }
  // The user block: header with the size of the HDF5 part and the checksum of the whole file,
  // the header's own digits read as zeros.
  std::error_code size_ec;
  const auto file_size = fs::file_size(tmp, size_ec);
  if (size_ec || file_size < kUserBlock)
    throw std::runtime_error(fmt::format("cannot write checkpoint '{}' (size)", tmp));
  const std::size_t body = static_cast<std::size_t>(file_size) - kUserBlock;
  std::FILE* f = std::fopen(tmp.c_str(), "r+b");
  if (!f) throw std::runtime_error(fmt::format("cannot reopen checkpoint '{}'", tmp));
  std::size_t bytes = 0;
  const std::uint64_t sum = file_checksum(f, kUserBlock, bytes, fnv1a(header_text(body, 0)));
  const std::string header = header_text(bytes, sum);
  const bool ok = bytes == body && std::fseek(f, 0, SEEK_SET) == 0 &&
                  std::fwrite(header.data(), 1, header.size(), f) == header.size() &&
                  std::fflush(f) == 0 && ::fsync(::fileno(f)) == 0;
  std::fclose(f);
  if (!ok) throw std::runtime_error(fmt::format("cannot write checkpoint '{}'", tmp));
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec)
    throw std::runtime_error(
        fmt::format("cannot rename '{}' to '{}': {}", tmp, path, ec.message()));
  const fs::path parent = fs::path(path).parent_path();
  fsync_path(parent.empty() ? "." : parent.string(), O_RDONLY | O_DIRECTORY);
}

State read(const std::string& path) {
  quiet_hdf5();
  const auto refuse = [&](const std::string& what) {
    return InputError(path, 0, "", "checkpoint refused: " + what);
  };
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw refuse("no such file");
  // 1. Header, size and checksum before libhdf5 sees the file. The checksum covers every byte of
  // the file: the header block (text and NUL padding) with its 16 digits read as '0', then the
  // HDF5 part.
  std::size_t file_bytes = 0;
  int file_version = 0;
  {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw refuse("cannot open the file");
    std::array<char, kUserBlock> block{};
    const std::size_t got = std::fread(block.data(), 1, block.size(), f);
    const auto fail = [&](const std::string& what) {
      std::fclose(f);
      return refuse(what);
    };
    if (got != block.size()) throw fail("shorter than its 512-byte header (truncated?)");
    const std::string head(block.data(), strnlen(block.data(), block.size()));
    if (head.rfind(kMagic, 0) != 0)
      throw fail("not an mpmcd checkpoint (no MPMCD-CHECKPOINT header)");
    int version = 0;
    unsigned long long want_bytes = 0, want_sum = 0;
    if (std::sscanf(head.c_str(), "MPMCD-CHECKPOINT %d\nbytes %llu\nfnv1a64 %llx", &version,
                    &want_bytes, &want_sum) != 3)
      throw fail("unreadable header");
    if (version < kOldestFormatVersion || version > kFormatVersion)
      throw fail(fmt::format("format version {}, this mpmcd reads versions {} to {}", version,
                             kOldestFormatVersion, kFormatVersion));
    file_version = version;
    const std::size_t digits = head.find(kSumKey);
    if (digits == std::string::npos || digits + kSumKey.size() + kSumDigits > head.size() ||
        !std::all_of(head.begin() + static_cast<long>(digits + kSumKey.size()),
                     head.begin() + static_cast<long>(digits + kSumKey.size() + kSumDigits),
                     [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) != 0; }))
      throw fail("unreadable header (checksum digits)");
    std::string zeroed(block.data(), block.size());
    zeroed.replace(digits + kSumKey.size(), kSumDigits, kSumDigits, '0');
    std::size_t bytes = 0;
    const std::uint64_t sum = file_checksum(f, kUserBlock, bytes, fnv1a(zeroed));
    std::fclose(f);
    if (bytes != want_bytes)
      throw refuse(
          fmt::format("the file holds {} bytes after its header, its header says {} "
                      "(truncated or appended to)",
                      bytes, want_bytes));
    file_bytes = kUserBlock + bytes;
    if (sum != want_sum)
      throw refuse(
          fmt::format("checksum mismatch (fnv1a64 {:016x}, header says {:016x}): the "
                      "file is corrupted",
                      sum, static_cast<std::uint64_t>(want_sum)));
  }
  // 2. Datasets, types and sizes.
  Reader r(path, file_bytes);
  State s;
  constexpr hsize_t any = Reader::kAny;
  if (r.text("/meta/format") != kMagic) r.fail("/meta/format", "not an mpmcd checkpoint");
  if (r.scalar<std::int32_t>("/meta/format_version") != file_version)
    r.fail("/meta/format_version", "not the version of the file's header");
  s.mpmcd_version = r.text("/meta/mpmcd_version");
  s.input_text = r.text("/meta/input_text");
  s.input_path = r.text("/meta/input_path");
  s.input_hash = r.scalar<std::uint64_t>("/meta/input_hash");
  s.reason = r.text("/meta/reason");
  s.dim = r.scalar<std::int32_t>("/meta/dim");
  if (s.dim != 2 && s.dim != 3) r.fail("/meta/dim", fmt::format("dimension {}", s.dim));
  const auto d = static_cast<hsize_t>(s.dim);
  s.step = r.scalar<std::int64_t>("/time/step");
  s.time = r.scalar<double>("/time/t");
  s.dt = r.scalar<double>("/time/dt");
  s.good_since_cut = r.scalar<std::int64_t>("/time/good_since_cut");
  s.failed_steps = r.scalar<std::int64_t>("/time/failed_steps");
  s.newton_iterations = r.scalar<std::int64_t>("/time/newton_iterations");
  s.next_vtu = r.scalar<double>("/output/next_vtu");
  s.next_csv = r.scalar<double>("/output/next_csv");
  s.csv_rows = r.scalar<std::int64_t>("/output/csv_rows");
  s.vtu_times = r.array<double>("/output/vtu_times", {any});
  s.grain = r.array<std::int32_t>("/points/grain", {any});
  const hsize_t n = s.grain.size();
  s.x = r.array<double>("/points/x", {n, d});
  s.v = r.array<double>("/points/v", {n, d});
  s.L = r.array<double>("/points/L", {n, d, d});
  s.F = r.array<double>("/points/F", {n, d, d});
  s.sigma = r.array<double>("/points/sigma", {n, d, d});
  s.domain = r.array<double>("/points/domain", {n, d, d});
  s.sigma_zz = r.array<double>("/points/sigma_zz", {n});
  s.mass = r.array<double>("/points/mass", {n});
  s.volume0 = r.array<double>("/points/volume0", {n});
  s.volume = r.array<double>("/points/volume", {n});
  s.history = r.array<double>("/points/history", {any});
  s.grain_begin = r.array<std::int64_t>("/grains/begin", {any});
  const hsize_t ng = s.grain_begin.size();
  s.grain_end = r.array<std::int64_t>("/grains/end", {ng});
  s.grain_material = r.array<std::int32_t>("/grains/material", {ng});
  s.grain_half_width = r.array<double>("/grains/half_width", {ng});
  s.grain_history_offset = r.array<std::int64_t>("/grains/history_offset", {ng});
  s.warm_node = r.array<std::int64_t>("/contact/warm_node", {any});
  const hsize_t nw = s.warm_node.size();
  s.warm_a = r.array<std::int32_t>("/contact/warm_a", {nw});
  s.warm_b = r.array<std::int32_t>("/contact/warm_b", {nw});
  s.warm_impulse = r.array<double>("/contact/warm_impulse", {nw, d});
  s.wall_point = r.array<double>("/walls/point", {any, d});
  s.wall_work = r.array<double>("/walls/work", {s.wall_point.size() / d});
  if (file_version >= 7) {
    s.loading_stage = r.array<double>("/loading/stage", {any});
    s.loading_control = r.array<std::int32_t>("/loading/control", {any});
    s.loading_wall = r.array<double>("/loading/wall", {any});
  }
  s.energy0 = r.scalar<double>("/time/energy0");
  s.contact_dissipation = r.scalar<double>("/time/contact_dissipation");
  s.kinetic0 = r.scalar<double>("/time/kinetic0");
  s.transfer_dissipation = r.scalar<double>("/time/transfer_dissipation");
  s.stress_work = r.scalar<double>("/time/stress_work");
  s.body_work = r.scalar<double>("/time/body_work");
  s.ranks = r.scalar<std::int32_t>("/parallel/ranks");
  s.scheme = r.text("/parallel/scheme");
  s.grain_owner = r.array<std::int32_t>("/parallel/grain_owner", {ng});
  s.grain_work = r.array<double>("/parallel/grain_work", {ng, parallel::kWorkPhases});
  s.threads = r.scalar<std::int32_t>("/parallel/threads");
  // 3. Consistency and the payload checksum.
  if (r.scalar<std::uint64_t>("/meta/payload_checksum") != payload_checksum(s))
    r.fail("/meta/payload_checksum", "payload checksum mismatch (corrupted data)");
  if (s.input_hash != fnv1a(s.input_text)) r.fail("/meta/input_hash", "input hash mismatch");
  if (s.step < 0 || !(s.time >= 0) || !(s.dt > 0) || s.good_since_cut < 0 || s.csv_rows < 0)
    r.fail("/time", "negative step, time, dt or counters");
  std::int64_t expect_begin = 0;
  for (std::size_t g = 0; g < ng; ++g) {
    if (s.grain_begin[g] != expect_begin || s.grain_end[g] < s.grain_begin[g] ||
        s.grain_end[g] > static_cast<std::int64_t>(n) || s.grain_material[g] < 0 ||
        s.grain_history_offset[g] < 0 ||
        s.grain_history_offset[g] > static_cast<std::int64_t>(s.history.size()))
      r.fail("/grains", fmt::format("grain {} has an inconsistent point or history range", g));
    for (std::int64_t p = s.grain_begin[g]; p < s.grain_end[g]; ++p)
      if (s.grain[p] != static_cast<std::int32_t>(g))
        r.fail("/points/grain", fmt::format("point {} is not in grain {}", p, g));
    expect_begin = s.grain_end[g];
  }
  if (expect_begin != static_cast<std::int64_t>(n))
    r.fail("/grains", "the grains do not cover every point");
  if (s.ranks < 1) r.fail("/parallel/ranks", fmt::format("{} ranks", s.ranks));
  if (s.threads < 1) r.fail("/parallel/threads", fmt::format("{} threads", s.threads));
  if (s.scheme != "partition" && s.scheme != "master")
    r.fail("/parallel/scheme", fmt::format("unknown scheme '{}'", s.scheme));
  for (std::size_t g = 0; g < ng; ++g) {
    const double* work = &s.grain_work[g * parallel::kWorkPhases];
    if (s.grain_owner[g] < 0 || s.grain_owner[g] >= s.ranks ||
        !std::all_of(work, work + parallel::kWorkPhases, [](double x) { return x >= 0; }))
      r.fail("/parallel", fmt::format("grain {} has owner {} of {} ranks or a negative work", g,
                                      s.grain_owner[g], s.ranks));
  }
  return s;
}

std::string header_for(std::string_view body) {
  const std::uint64_t sum = fnv1a(body, fnv1a(header_text(body.size(), 0)));
  return header_text(body.size(), sum);
}

std::string file_name(const std::string& name, std::int64_t step) {
  return fmt::format("{}_checkpoint_{:09d}.h5", name, step);
}

std::vector<std::string> list(const std::string& folder, const std::string& name) {
  std::vector<std::string> out;
  std::error_code ec;
  const std::string prefix = name + "_checkpoint_";
  for (const auto& e : fs::directory_iterator(folder, ec)) {
    const std::string f = e.path().filename().string();
    if (f.size() == prefix.size() + 12 && f.rfind(prefix, 0) == 0 &&
        f.compare(f.size() - 3, 3, ".h5") == 0 &&
        std::all_of(f.begin() + static_cast<long>(prefix.size()), f.end() - 3,
                    [](char c) { return c >= '0' && c <= '9'; }))
      out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());  // zero-padded steps: lexical order = step order
  return out;
}

void prune(const std::string& folder, const std::string& name, int keep) {
  std::error_code ec;
  const auto all = list(folder, name);
  for (std::size_t k = 0; k + static_cast<std::size_t>(std::max(keep, 1)) < all.size(); ++k)
    fs::remove(all[k], ec);
  const std::string prefix = name + "_checkpoint_";
  for (const auto& e : fs::directory_iterator(folder, ec)) {
    const std::string f = e.path().filename().string();
    if (f.rfind(prefix, 0) == 0 && f.size() > 7 && f.compare(f.size() - 7, 7, ".h5.tmp") == 0)
      fs::remove(e.path(), ec);
  }
}

}  // namespace mpmcd::checkpoint

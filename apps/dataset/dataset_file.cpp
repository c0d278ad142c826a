#include "apps/dataset/dataset_file.h"

// HDF5's C API: the property lists (time tracking, chunks, filters) are
// plain calls there; h5py and the C++ API read what it writes.
#include <hdf5.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <utility>

#include "core/time.h"
#include "pipeline/training/dataset_io.h"

namespace uavsim::sim {
namespace {

using pipeline::CameraObservation;
using pipeline::Episode;
using pipeline::Sample;

constexpr unsigned kGzipLevel = 4;
constexpr hsize_t kRowsPerChunk = 4096;  // points and latents: rows per chunk

// A failed HDF5 call, with the file it was writing.
class Fail {
 public:
  explicit Fail(std::string path) : path_(std::move(path)) {}
  [[noreturn]] void operator()(const std::string& what) const {
    throw std::runtime_error(path_ + ": HDF5 could not " + what);
  }
  [[noreturn]] void Invalid(const std::string& what) const {
    throw std::invalid_argument(path_ + ": " + what);
  }

 private:
  std::string path_;
};

// An HDF5 identifier closed with its kind's close function.
class Id {
 public:
  Id(hid_t id, herr_t (*close)(hid_t), const Fail& fail, const std::string& what)
      : id_(id), close_(close) {
    if (id_ < 0) fail(what);
  }
  ~Id() {
    if (id_ >= 0) close_(id_);
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  Id(Id&& o) noexcept : id_(std::exchange(o.id_, -1)), close_(o.close_) {}
  hid_t get() const { return id_; }
  // Closes now; the status says whether it worked (a file's last writes).
  herr_t Close() { return close_(std::exchange(id_, -1)); }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

void Check(herr_t status, const Fail& fail, const std::string& what) {
  if (status < 0) fail(what);
}

// The file and memory types of each element type written.
template <class T>
struct Types;
template <>
struct Types<std::uint8_t> {
  static hid_t File() { return H5T_STD_U8LE; }
  static hid_t Memory() { return H5T_NATIVE_UINT8; }
};
template <>
struct Types<std::uint32_t> {
  static hid_t File() { return H5T_STD_U32LE; }
  static hid_t Memory() { return H5T_NATIVE_UINT32; }
};
template <>
struct Types<std::int64_t> {
  static hid_t File() { return H5T_STD_I64LE; }
  static hid_t Memory() { return H5T_NATIVE_INT64; }
};
template <>
struct Types<std::uint64_t> {
  static hid_t File() { return H5T_STD_U64LE; }
  static hid_t Memory() { return H5T_NATIVE_UINT64; }
};
template <>
struct Types<float> {
  static hid_t File() { return H5T_IEEE_F32LE; }
  static hid_t Memory() { return H5T_NATIVE_FLOAT; }
};
template <>
struct Types<double> {
  static hid_t File() { return H5T_IEEE_F64LE; }
  static hid_t Memory() { return H5T_NATIVE_DOUBLE; }
};

// Variable-length UTF-8 strings (h5py: str for attributes, bytes for
// datasets unless read with .asstr()).
Id StringType(const Fail& fail) {
  Id t(H5Tcopy(H5T_C_S1), H5Tclose, fail, "make a string type");
  Check(H5Tset_size(t.get(), H5T_VARIABLE), fail, "make a string type");
  Check(H5Tset_cset(t.get(), H5T_CSET_UTF8), fail, "make a string type");
  return t;
}

// Where groups, datasets and attributes go, and how: no time stamps
// anywhere (byte-identical files), large arrays compressed.
class Writer {
 public:
  explicit Writer(const std::string& path) : fail_(path) {}
  const Fail& fail() const { return fail_; }

  Id Group(hid_t parent, const std::string& name) const {
    Id gcpl(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, fail_, "make a property list");
    Check(H5Pset_obj_track_times(gcpl.get(), false), fail_, "turn off time tracking");
    return Id(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose,
              fail_, "create group " + name);
  }

  // A dataset of shape `dims` from row-major `data` (dims' product values).
  // Compressed ones are chunked by `chunk_rows` rows (the other dimensions
  // whole) unless empty.
  template <class T>
  void Array(hid_t parent, const std::string& name, const std::vector<hsize_t>& dims, const T* data,
             bool compress = false, hsize_t chunk_rows = kRowsPerChunk) const {
    hsize_t count = 1;
    for (hsize_t d : dims) count *= d;
    Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose, fail_,
             "make the shape of " + name);
    Id dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, fail_, "make a property list");
    Check(H5Pset_obj_track_times(dcpl.get(), false), fail_, "turn off time tracking");
    if (compress && count > 0) {
      std::vector<hsize_t> chunk = dims;
      chunk[0] = std::min(dims[0], chunk_rows);
      Check(H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data()), fail_,
            "chunk " + name);
      Check(H5Pset_shuffle(dcpl.get()), fail_, "shuffle " + name);
      Check(H5Pset_deflate(dcpl.get(), kGzipLevel), fail_, "compress " + name);
    }
    Id set(H5Dcreate2(parent, name.c_str(), Types<T>::File(), space.get(), H5P_DEFAULT, dcpl.get(),
                      H5P_DEFAULT),
           H5Dclose, fail_, "create dataset " + name);
    if (count > 0)
      Check(H5Dwrite(set.get(), Types<T>::Memory(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data), fail_,
            "write dataset " + name);
  }
  template <class T>
  void Array(hid_t parent, const std::string& name, const std::vector<hsize_t>& dims,
             const std::vector<T>& data, bool compress = false,
             hsize_t chunk_rows = kRowsPerChunk) const {
    Array(parent, name, dims, data.data(), compress, chunk_rows);
  }
  // Rows of three: [n, 3].
  void Vectors(hid_t parent, const std::string& name, const std::vector<Eigen::Vector3d>& v) const {
    std::vector<double> flat;
    flat.reserve(3 * v.size());
    for (const Eigen::Vector3d& p : v) flat.insert(flat.end(), {p.x(), p.y(), p.z()});
    Array(parent, name, {v.size(), 3}, flat);
  }
  void Strings(hid_t parent, const std::string& name, const std::vector<std::string>& v) const {
    const Id type = StringType(fail_);
    const hsize_t n = v.size();
    Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, fail_, "make the shape of " + name);
    Id dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, fail_, "make a property list");
    Check(H5Pset_obj_track_times(dcpl.get(), false), fail_, "turn off time tracking");
    Id set(H5Dcreate2(parent, name.c_str(), type.get(), space.get(), H5P_DEFAULT, dcpl.get(),
                      H5P_DEFAULT),
           H5Dclose, fail_, "create dataset " + name);
    std::vector<const char*> p;
    for (const std::string& s : v) p.push_back(s.c_str());
    if (n > 0)
      Check(H5Dwrite(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), fail_,
            "write dataset " + name);
  }

  template <class T>
  void Attribute(hid_t parent, const std::string& name, T value) const {
    Id space(H5Screate(H5S_SCALAR), H5Sclose, fail_, "make a scalar");
    Id a(H5Acreate2(parent, name.c_str(), Types<T>::File(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
         H5Aclose, fail_, "create attribute " + name);
    Check(H5Awrite(a.get(), Types<T>::Memory(), &value), fail_, "write attribute " + name);
  }
  void Attribute(hid_t parent, const std::string& name, const std::string& value) const {
    const Id type = StringType(fail_);
    Id space(H5Screate(H5S_SCALAR), H5Sclose, fail_, "make a scalar");
    Id a(H5Acreate2(parent, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
         H5Aclose, fail_, "create attribute " + name);
    const char* p = value.c_str();
    Check(H5Awrite(a.get(), type.get(), &p), fail_, "write attribute " + name);
  }
  void Attribute(hid_t parent, const std::string& name,
                 const std::vector<std::string>& values) const {
    const Id type = StringType(fail_);
    const hsize_t n = values.size();
    Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, fail_, "make the shape of " + name);
    Id a(H5Acreate2(parent, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
         H5Aclose, fail_, "create attribute " + name);
    std::vector<const char*> p;
    for (const std::string& s : values) p.push_back(s.c_str());
    Check(H5Awrite(a.get(), type.get(), p.data()), fail_, "write attribute " + name);
  }

 private:
  Fail fail_;
};

// The channels of each point modality, as PointObservation documents them.
std::vector<std::string> ChannelNames(core::Modality m) {
  if (m == core::Modality::kLidar) return {"x_m", "y_m", "z_m", "intensity"};
  return {"x_m", "y_m", "z_m", "radial_velocity_mps", "snr_db"};
}

void WriteCamera(const Writer& w, hid_t episode, const Episode& e,
                 const std::vector<std::int64_t>& rows) {
  constexpr std::size_t kPx = CameraObservation::kCropPx;
  const std::size_t n = rows.size();
  std::vector<double> t_observation;
  std::vector<std::uint8_t> left, right, detected;
  std::vector<float> centre_left, centre_right, side_left, side_right;
  std::vector<Eigen::Vector3d> eye_left, eye_right, bearing_left, bearing_right;
  left.reserve(n * kPx * kPx);
  right.reserve(n * kPx * kPx);
  for (std::int64_t row : rows) {
    const CameraObservation& c = *e.samples[static_cast<std::size_t>(row)].camera;
    if (c.crop_left.size() != kPx * kPx || c.crop_right.size() != kPx * kPx)
      w.fail().Invalid("a camera frame's crops are not 128 x 128 (frame " + std::to_string(row) +
                       ")");
    t_observation.push_back(c.t_s);
    for (float v : c.crop_left) left.push_back(pipeline::GreyByte(v));
    for (float v : c.crop_right) right.push_back(pipeline::GreyByte(v));
    detected.push_back(c.detected ? 1 : 0);
    centre_left.insert(centre_left.end(), {c.centre_left_px.x(), c.centre_left_px.y()});
    centre_right.insert(centre_right.end(), {c.centre_right_px.x(), c.centre_right_px.y()});
    side_left.push_back(c.side_left_px);
    side_right.push_back(c.side_right_px);
    eye_left.push_back(c.eye_left_w);
    eye_right.push_back(c.eye_right_w);
    bearing_left.push_back(c.bearing_left_w);
    bearing_right.push_back(c.bearing_right_w);
  }
  const Id g = w.Group(episode, "camera");
  w.Array(g.get(), "frame", {n}, rows);
  w.Array(g.get(), "t_observation_s", {n}, t_observation);
  // One crop a chunk: a reader that wants one crop inflates 16 KB.
  w.Array(g.get(), "crop_left", {n, kPx, kPx}, left, true, 1);
  w.Array(g.get(), "crop_right", {n, kPx, kPx}, right, true, 1);
  w.Array(g.get(), "detected", {n}, detected);
  w.Array(g.get(), "centre_left_px", {n, 2}, centre_left);
  w.Array(g.get(), "centre_right_px", {n, 2}, centre_right);
  w.Array(g.get(), "side_left_px", {n}, side_left);
  w.Array(g.get(), "side_right_px", {n}, side_right);
  w.Vectors(g.get(), "eye_left_m", eye_left);
  w.Vectors(g.get(), "eye_right_m", eye_right);
  w.Vectors(g.get(), "bearing_left", bearing_left);
  w.Vectors(g.get(), "bearing_right", bearing_right);
}

void WritePoints(const Writer& w, hid_t episode, const Episode& e, core::Modality m,
                 const std::vector<std::int64_t>& rows) {
  const std::size_t channels = m == core::Modality::kLidar ? 4 : 5;
  std::vector<double> t_observation;
  std::vector<Eigen::Vector3d> sensor;
  std::vector<std::int64_t> offsets{0};
  std::vector<float> points;
  for (std::int64_t row : rows) {
    const pipeline::PointObservation& p = *e.samples[static_cast<std::size_t>(row)].points;
    if (p.channels != static_cast<int>(channels) || p.values.size() % channels != 0)
      w.fail().Invalid(std::string("a ") + core::ModalityName(m) + " frame has " +
                       std::to_string(p.values.size()) + " values of " +
                       std::to_string(p.channels) + " channels where " + std::to_string(channels) +
                       " are expected (frame " + std::to_string(row) + ")");
    t_observation.push_back(p.t_s);
    sensor.push_back(p.sensor_position_w);
    points.insert(points.end(), p.values.begin(), p.values.end());
    offsets.push_back(static_cast<std::int64_t>(points.size() / channels));
  }
  const Id g = w.Group(episode, core::ModalityName(m));
  w.Array(g.get(), "frame", {rows.size()}, rows);
  w.Array(g.get(), "t_observation_s", {rows.size()}, t_observation);
  w.Vectors(g.get(), "sensor_position_m", sensor);
  w.Array(g.get(), "offsets", {offsets.size()}, offsets);
  const hsize_t count = points.size() / channels;
  w.Array(g.get(), "points", {count, channels}, points, true);
  const Id set(H5Dopen2(g.get(), "points", H5P_DEFAULT), H5Dclose, w.fail(), "open points");
  w.Attribute(set.get(), "channels", ChannelNames(m));
}

void WriteEpisode(const Writer& w, hid_t parent, std::size_t index, const Episode& e,
                  std::size_t node_count, const std::vector<std::vector<float>>* latents,
                  std::int64_t latent_dim, int part) {
  char name[16];
  std::snprintf(name, sizeof name, "%06zu", index);
  const Id g = w.Group(parent, name);
  w.Attribute(g.get(), "index", static_cast<std::int64_t>(index));
  w.Attribute(g.get(), "label", e.label);
  w.Attribute(g.get(), "weather", pipeline::WeatherOf(e));
  w.Attribute(g.get(), "window_s", e.window_s);
  w.Attribute(g.get(), "raw_modalities", e.raw_modalities);
  static const char* const kParts[] = {"train", "validation", "test"};
  if (part >= 0) w.Attribute(g.get(), "part", std::string(kParts[part]));
  w.Vectors(g.get(), "window_truth_m", e.window_truth);

  // The frames table, and each modality's rows of it.
  const std::size_t n = e.samples.size();
  std::vector<double> t_capture, t_arrival;
  std::vector<std::uint8_t> fate, on_time, modality;
  std::vector<std::uint32_t> node;
  std::vector<std::int64_t> window;
  std::vector<Eigen::Vector3d> truth;
  std::vector<std::int64_t> rows[core::kModalityCount];
  const core::SimTime window_ns = core::Seconds(e.window_s);
  for (std::size_t i = 0; i < n; ++i) {
    const Sample& s = e.samples[i];
    if (s.node >= node_count)
      w.fail().Invalid("a frame of episode " + std::to_string(index) + " names node " +
                       std::to_string(s.node) + " of " + std::to_string(node_count));
    if ((s.modality == core::Modality::kCamera) != s.camera.has_value() ||
        (s.modality != core::Modality::kCamera) != s.points.has_value())
      w.fail().Invalid(std::string("a ") + core::ModalityName(s.modality) +
                       " frame must carry exactly its own observation");
    t_capture.push_back(s.t_s);
    t_arrival.push_back(s.t_arrival_s);
    fate.push_back(static_cast<std::uint8_t>(s.fate));
    on_time.push_back(s.on_time ? 1 : 0);
    modality.push_back(static_cast<std::uint8_t>(s.modality));
    node.push_back(s.node);
    // As the edge and TE-Align number windows: on integer nanoseconds.
    window.push_back(core::Seconds(s.t_s) / window_ns + 1);
    truth.push_back(s.truth_m);
    rows[static_cast<int>(s.modality)].push_back(static_cast<std::int64_t>(i));
  }
  {
    const Id f = w.Group(g.get(), "frames");
    w.Array(f.get(), "t_capture_s", {n}, t_capture);
    w.Array(f.get(), "t_arrival_s", {n}, t_arrival);
    w.Array(f.get(), "fate", {n}, fate);
    w.Array(f.get(), "on_time", {n}, on_time);
    w.Array(f.get(), "modality", {n}, modality);
    w.Array(f.get(), "node", {n}, node);
    w.Array(f.get(), "window", {n}, window);
    w.Vectors(f.get(), "truth_m", truth);
    if (latents) {
      if (latents->size() != n)
        w.fail().Invalid("episode " + std::to_string(index) + " has " + std::to_string(n) +
                         " frames but " + std::to_string(latents->size()) + " latents");
      std::vector<float> flat;
      flat.reserve(n * static_cast<std::size_t>(latent_dim));
      for (const std::vector<float>& z : *latents) {
        if (static_cast<std::int64_t>(z.size()) != latent_dim)
          w.fail().Invalid("a latent of " + std::to_string(z.size()) + " values, expected " +
                           std::to_string(latent_dim));
        flat.insert(flat.end(), z.begin(), z.end());
      }
      w.Array(f.get(), "latent", {n, static_cast<hsize_t>(latent_dim)}, flat, true);
    }
  }
  WriteCamera(w, g.get(), e, rows[static_cast<int>(core::Modality::kCamera)]);
  WritePoints(w, g.get(), e, core::Modality::kLidar,
              rows[static_cast<int>(core::Modality::kLidar)]);
  WritePoints(w, g.get(), e, core::Modality::kRadar,
              rows[static_cast<int>(core::Modality::kRadar)]);
}

}  // namespace

void WriteDatasetFile(const std::string& path, const DatasetHeader& header,
                      const std::vector<DatasetNode>& nodes,
                      const std::vector<pipeline::Episode>& episodes,
                      const std::vector<std::vector<std::vector<float>>>& latents,
                      const std::function<void(std::size_t)>& episode_written) {
  const Writer w(path);
  if (!latents.empty() && latents.size() != episodes.size())
    w.fail().Invalid("latents for " + std::to_string(latents.size()) + " episodes, not " +
                     std::to_string(episodes.size()));
  if (!latents.empty() && header.latent_dim <= 0) w.fail().Invalid("latents without a latent size");
  if (!header.parts.empty() && header.parts.size() != episodes.size())
    w.fail().Invalid("parts for " + std::to_string(header.parts.size()) + " episodes, not " +
                     std::to_string(episodes.size()));
  for (int part : header.parts)
    if (part < 0 || part > 2)
      w.fail().Invalid("part " + std::to_string(part) + " is not 0, 1 or 2");
  // Errors become exceptions here, not messages of HDF5's own on stderr.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  // The root group's creation properties are the file's.
  Id fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose, w.fail(), "make a property list");
  Check(H5Pset_obj_track_times(fcpl.get(), false), w.fail(), "turn off time tracking");
  Id file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), H5P_DEFAULT), H5Fclose, w.fail(),
          "create the file");
  {
    const Id root(H5Gopen2(file.get(), "/", H5P_DEFAULT), H5Gclose, w.fail(), "open /");
    const hid_t r = root.get();
    w.Attribute(r, "schema_version", DatasetHeader::kSchemaVersion);
    w.Attribute(r, "uavsim_version", header.uavsim_version);
    w.Attribute(r, "uavsim_git_hash", header.uavsim_git_hash);
    w.Attribute(r, "scenario_file", header.scenario_file);
    w.Attribute(r, "scenario", header.scenario);
    w.Attribute(r, "seed", header.seed);
    w.Attribute(r, "episodes", static_cast<std::int64_t>(episodes.size()));
    w.Attribute(r, "episode_s", header.episode_s);
    w.Attribute(r, "window_s", header.window_s);
    w.Attribute(r, "latent_dim", latents.empty() ? std::int64_t{0} : header.latent_dim);
    w.Attribute(r, "model", header.model);
    w.Attribute(r, "modalities", std::vector<std::string>{"camera", "lidar", "radar"});
    w.Attribute(r, "fates", std::vector<std::string>{"on_time", "late", "lost", "in_flight"});

    const Id g = w.Group(r, "nodes");
    std::vector<std::string> ids;
    std::vector<std::uint8_t> modality;
    std::vector<Eigen::Vector3d> position, rpy;
    std::vector<double> rate;
    for (const DatasetNode& node : nodes) {
      ids.push_back(node.id);
      modality.push_back(static_cast<std::uint8_t>(node.modality));
      position.push_back(node.position_m);
      rpy.push_back(node.rpy_deg);
      rate.push_back(node.rate_hz);
    }
    w.Strings(g.get(), "id", ids);
    w.Array(g.get(), "modality", {nodes.size()}, modality);
    w.Vectors(g.get(), "position_m", position);
    w.Vectors(g.get(), "rpy_deg", rpy);
    w.Array(g.get(), "rate_hz", {nodes.size()}, rate);

    const Id all = w.Group(r, "episodes");
    for (std::size_t i = 0; i < episodes.size(); ++i) {
      WriteEpisode(w, all.get(), i, episodes[i], nodes.size(),
                   latents.empty() ? nullptr : &latents[i], header.latent_dim,
                   header.parts.empty() ? -1 : header.parts[i]);
      if (episode_written) episode_written(i + 1);
    }
  }
  Check(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), w.fail(), "write the file");
  if (file.Close() < 0) w.fail()("close the file");
}

}  // namespace uavsim::sim

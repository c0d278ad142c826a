// `uavsim dataset` (apps/dataset/dataset_export.h, apps/dataset/dataset_file.h): the HDF5 file
// read back with HDF5's C++ API (plain reads, independent of the writer) and
// compared field by field with the episodes the same command keeps in its
// --data file; the same bytes whatever --jobs or mpirun; latents as the
// node encoder gives them; h5py reads it; bad input refused with one line,
// exit 2 and nothing left behind.
#include <H5Cpp.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "apps/dataset/dataset_file.h"
#include "core/json_io.h"
#include "pipeline/model_bundle.h"
#include "pipeline/torch_runtime.h"
#include "pipeline/training/dataset.h"
#include "pipeline/training/dataset_io.h"
#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::pipeline::Episode;
using uavsim::pipeline::Sample;
using uavsim::pipeline::SampleFate;
using uavsim::testing::FindOnPath;
using uavsim::testing::ReadFile;
using uavsim::testing::RunCli;
using uavsim::testing::RunProgram;
using uavsim::testing::TempDir;
using uavsim::testing::WriteFile;

namespace {

const std::string kDefault = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/default.json";
const std::string kModel = std::string(UAVSIM_SOURCE_DIR) + "/models/default";

// A dataset of the file: its shape and values, row-major.
template <class T>
struct Array {
  std::vector<hsize_t> dims;
  std::vector<T> v;
  hsize_t rows() const { return dims.empty() ? 0 : dims[0]; }
};

template <class T>
Array<T> Read(const H5::H5File& f, const std::string& path, const H5::PredType& type) {
  const H5::DataSet set = f.openDataSet(path);
  const H5::DataSpace space = set.getSpace();
  Array<T> a;
  a.dims.resize(static_cast<std::size_t>(space.getSimpleExtentNdims()));
  space.getSimpleExtentDims(a.dims.data());
  hsize_t n = 1;
  for (hsize_t d : a.dims) n *= d;
  a.v.resize(n);
  if (n > 0) set.read(a.v.data(), type);
  return a;
}

// The file type's class and size of a dataset (its dtype).
std::pair<H5T_class_t, std::size_t> TypeOf(const H5::H5File& f, const std::string& path) {
  const H5::DataType t = f.openDataSet(path).getDataType();
  return {t.getClass(), t.getSize()};
}

std::string StringAttribute(const H5::H5Object& o, const std::string& name) {
  const H5::Attribute a = o.openAttribute(name);
  H5std_string s;
  a.read(a.getStrType(), s);
  return s;
}

template <class T>
T NumberAttribute(const H5::H5Object& o, const std::string& name, const H5::PredType& type) {
  T v{};
  o.openAttribute(name).read(type, &v);
  return v;
}

// A variable-length string dataset or attribute of one dimension.
std::vector<std::string> Strings(const H5::DataSet& set) {
  const H5::DataSpace space = set.getSpace();
  hsize_t n = 0;
  space.getSimpleExtentDims(&n);
  std::vector<char*> p(n);
  const H5::StrType type = set.getStrType();
  if (n > 0) set.read(p.data(), type);
  std::vector<std::string> out(p.begin(), p.end());
  if (n > 0) H5::DataSet::vlenReclaim(p.data(), type, space);
  return out;
}

std::vector<std::string> Strings(const H5::Attribute& a) {
  const H5::DataSpace space = a.getSpace();
  hsize_t n = 0;
  space.getSimpleExtentDims(&n);
  std::vector<char*> p(n);
  const H5::StrType type = a.getStrType();
  a.read(type, p.data());
  std::vector<std::string> out(p.begin(), p.end());
  H5::DataSet::vlenReclaim(p.data(), type, space);
  return out;
}

bool SameDouble(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The rows of `modality` in the episode's samples.
std::vector<std::int64_t> RowsOf(const Episode& e, uavsim::core::Modality m) {
  std::vector<std::int64_t> rows;
  for (std::size_t i = 0; i < e.samples.size(); ++i)
    if (e.samples[i].modality == m) rows.push_back(static_cast<std::int64_t>(i));
  return rows;
}

void CheckVectors(const Array<double>& a, std::size_t row, const Eigen::Vector3d& v) {
  REQUIRE(a.dims.size() == 2);
  REQUIRE(a.dims[1] == 3);
  CHECK(a.v[3 * row] == v.x());
  CHECK(a.v[3 * row + 1] == v.y());
  CHECK(a.v[3 * row + 2] == v.z());
}

// Every field of episode `e` as stored in group /episodes/NNNNNN of `f`.
void CheckEpisode(const H5::H5File& f, std::size_t index, const Episode& e) {
  using uavsim::core::Modality;
  const auto& U8 = H5::PredType::NATIVE_UINT8;
  const auto& U32 = H5::PredType::NATIVE_UINT32;
  const auto& I64 = H5::PredType::NATIVE_INT64;
  const auto& F32 = H5::PredType::NATIVE_FLOAT;
  const auto& F64 = H5::PredType::NATIVE_DOUBLE;
  char name[32];
  std::snprintf(name, sizeof name, "/episodes/%06zu/", index);
  const std::string g = name;
  INFO(g);
  const H5::Group group = f.openGroup(g);
  CHECK(NumberAttribute<std::int64_t>(group, "index", I64) == static_cast<std::int64_t>(index));
  CHECK(StringAttribute(group, "label") == e.label);
  CHECK(StringAttribute(group, "weather") == uavsim::pipeline::WeatherOf(e));
  CHECK(NumberAttribute<double>(group, "window_s", F64) == e.window_s);
  CHECK(StringAttribute(group, "part") == "train");  // two flights: none held out

  const auto window_truth = Read<double>(f, g + "window_truth_m", F64);
  REQUIRE(window_truth.rows() == e.window_truth.size());
  for (std::size_t k = 0; k < e.window_truth.size(); ++k)
    CheckVectors(window_truth, k, e.window_truth[k]);

  const std::size_t n = e.samples.size();
  const auto t_capture = Read<double>(f, g + "frames/t_capture_s", F64);
  const auto t_arrival = Read<double>(f, g + "frames/t_arrival_s", F64);
  const auto fate = Read<std::uint8_t>(f, g + "frames/fate", U8);
  const auto on_time = Read<std::uint8_t>(f, g + "frames/on_time", U8);
  const auto modality = Read<std::uint8_t>(f, g + "frames/modality", U8);
  const auto node = Read<std::uint32_t>(f, g + "frames/node", U32);
  const auto window = Read<std::int64_t>(f, g + "frames/window", I64);
  const auto truth = Read<double>(f, g + "frames/truth_m", F64);
  for (const auto* dims : {&t_capture.dims, &t_arrival.dims, &fate.dims, &on_time.dims,
                           &modality.dims, &node.dims, &window.dims})
    CHECK(*dims == std::vector<hsize_t>{n});
  CHECK(truth.dims == std::vector<hsize_t>{n, 3});
  std::size_t arrived = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Sample& s = e.samples[i];
    INFO("frame " << i);
    CHECK(t_capture.v[i] == s.t_s);
    CHECK(SameDouble(t_arrival.v[i], s.t_arrival_s));
    CHECK(fate.v[i] == static_cast<std::uint8_t>(s.fate));
    CHECK(on_time.v[i] == (s.on_time ? 1 : 0));
    CHECK(modality.v[i] == static_cast<std::uint8_t>(s.modality));
    CHECK(node.v[i] == s.node);
    CheckVectors(truth, i, s.truth_m);
    // The window k with (k - 1) t^w <= t < k t^w.
    const double w = e.window_s;
    CHECK(static_cast<double>(window.v[i] - 1) * w <= s.t_s + 1e-9);
    CHECK(s.t_s < static_cast<double>(window.v[i]) * w - 1e-9);
    // Fates as the edge saw them: on time exactly when on_time; an arrival
    // time exactly for what arrived, after its capture; a simulated
    // episode knows every fate.
    CHECK((fate.v[i] == 0) == (on_time.v[i] == 1));
    CHECK(fate.v[i] <= 3);
    const bool came = fate.v[i] == 0 || fate.v[i] == 1;
    CHECK(std::isnan(t_arrival.v[i]) == !came);
    if (came) CHECK(t_arrival.v[i] > t_capture.v[i]);
    arrived += came;
    // Late: after its window's deadline (its end plus the late allowance,
    // which is at least 0).
    if (fate.v[i] == 1) CHECK(t_arrival.v[i] > static_cast<double>(window.v[i]) * w);
  }
  CHECK(arrived > 0);

  // The camera frames.
  const std::vector<std::int64_t> cam_rows = RowsOf(e, Modality::kCamera);
  const std::size_t nc = cam_rows.size();
  CHECK(Read<std::int64_t>(f, g + "camera/frame", I64).v == cam_rows);
  const auto left = Read<std::uint8_t>(f, g + "camera/crop_left", U8);
  const auto right = Read<std::uint8_t>(f, g + "camera/crop_right", U8);
  CHECK(left.dims == std::vector<hsize_t>{nc, 128, 128});
  CHECK(right.dims == std::vector<hsize_t>{nc, 128, 128});
  const auto cam_t = Read<double>(f, g + "camera/t_observation_s", F64);
  CHECK(cam_t.dims == std::vector<hsize_t>{nc});
  const auto detected = Read<std::uint8_t>(f, g + "camera/detected", U8);
  const auto centre_left = Read<float>(f, g + "camera/centre_left_px", F32);
  const auto centre_right = Read<float>(f, g + "camera/centre_right_px", F32);
  const auto side_left = Read<float>(f, g + "camera/side_left_px", F32);
  const auto side_right = Read<float>(f, g + "camera/side_right_px", F32);
  const auto eye_left = Read<double>(f, g + "camera/eye_left_m", F64);
  const auto eye_right = Read<double>(f, g + "camera/eye_right_m", F64);
  const auto bearing_left = Read<double>(f, g + "camera/bearing_left", F64);
  const auto bearing_right = Read<double>(f, g + "camera/bearing_right", F64);
  CHECK(centre_left.dims == std::vector<hsize_t>{nc, 2});
  CHECK(side_right.dims == std::vector<hsize_t>{nc});
  for (std::size_t j = 0; j < nc; ++j) {
    const Sample& s = e.samples[static_cast<std::size_t>(cam_rows[j])];
    const auto& c = *s.camera;
    INFO("camera frame " << j);
    CHECK(cam_t.v[j] == c.t_s);
    CHECK(c.t_s == s.t_s);  // the camera's observation is of its capture time
    constexpr std::size_t kCrop = 128 * 128;
    const std::uint8_t* l = left.v.data() + j * kCrop;
    const std::uint8_t* r = right.v.data() + j * kCrop;
    // The crops' bytes are the episode file's, and lossless: they give back
    // the pre-processor's floats bit for bit.
    CHECK(uavsim::pipeline::GreyFloats(l, kCrop) == c.crop_left);
    CHECK(uavsim::pipeline::GreyFloats(r, kCrop) == c.crop_right);
    CHECK(detected.v[j] == (c.detected ? 1 : 0));
    CHECK(centre_left.v[2 * j] == c.centre_left_px.x());
    CHECK(centre_left.v[2 * j + 1] == c.centre_left_px.y());
    CHECK(centre_right.v[2 * j] == c.centre_right_px.x());
    CHECK(centre_right.v[2 * j + 1] == c.centre_right_px.y());
    CHECK(side_left.v[j] == c.side_left_px);
    CHECK(side_right.v[j] == c.side_right_px);
    CheckVectors(eye_left, j, c.eye_left_w);
    CheckVectors(eye_right, j, c.eye_right_w);
    CheckVectors(bearing_left, j, c.bearing_left_w);
    CheckVectors(bearing_right, j, c.bearing_right_w);
  }

  // The point clouds.
  for (const Modality m : {Modality::kLidar, Modality::kRadar}) {
    const std::string p = g + uavsim::core::ModalityName(m) + "/";
    INFO(p);
    const std::vector<std::int64_t> rows = RowsOf(e, m);
    const hsize_t channels = m == Modality::kLidar ? 4 : 5;
    CHECK(Read<std::int64_t>(f, p + "frame", I64).v == rows);
    const auto t_obs = Read<double>(f, p + "t_observation_s", F64);
    REQUIRE(t_obs.v.size() == rows.size());
    const auto sensor = Read<double>(f, p + "sensor_position_m", F64);
    const auto offsets = Read<std::int64_t>(f, p + "offsets", I64);
    const auto points = Read<float>(f, p + "points", F32);
    REQUIRE(offsets.v.size() == rows.size() + 1);
    REQUIRE(points.dims.size() == 2);
    CHECK(points.dims[1] == channels);
    CHECK(offsets.v.front() == 0);
    CHECK(static_cast<hsize_t>(offsets.v.back()) == points.dims[0]);
    for (std::size_t j = 0; j < rows.size(); ++j) {
      const auto& obs = *e.samples[static_cast<std::size_t>(rows[j])].points;
      // LiDAR: when the target was swept, within the sweep that began at
      // the capture time (one sweep is 1 / rate_hz = 0.1 s in the default
      // scenario).
      const double t_capture = e.samples[static_cast<std::size_t>(rows[j])].t_s;
      CHECK(t_obs.v[j] == obs.t_s);
      CHECK(obs.t_s >= t_capture);
      CHECK(obs.t_s < t_capture + 0.1);
      CheckVectors(sensor, j, obs.sensor_position_w);
      const auto from = static_cast<std::size_t>(offsets.v[j]) * channels;
      const auto to = static_cast<std::size_t>(offsets.v[j + 1]) * channels;
      CHECK(std::vector<float>(points.v.begin() + static_cast<std::ptrdiff_t>(from),
                               points.v.begin() + static_cast<std::ptrdiff_t>(to)) == obs.values);
    }
    const H5::Attribute names = f.openDataSet(p + "points").openAttribute("channels");
    CHECK(Strings(names) ==
          (m == Modality::kLidar
               ? std::vector<std::string>{"x_m", "y_m", "z_m", "intensity"}
               : std::vector<std::string>{"x_m", "y_m", "z_m", "radial_velocity_mps", "snr_db"}));
  }
}

// The files and folders directly in `dir`.
std::set<std::string> Listing(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

// A python3 that imports h5py: Debian's (/usr/bin/python3, where
// python3-h5py installs), else the first on PATH; "" if neither does.
std::string PythonWithH5py() {
  for (const std::string& python : {std::string("/usr/bin/python3"), FindOnPath("python3")})
    if (!python.empty() && fs::exists(python) &&
        RunProgram({python, "-c", "import h5py"}).exit_code == 0)
      return python;
  return "";
}

std::size_t Lines(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

}  // namespace

TEST_CASE(
    "CLI: dataset writes every field of the training episodes to HDF5, the same bytes whatever "
    "--jobs or mpirun, with the node encoders' latents given a model",
    "[sim][dataset][slow]") {
  const std::string dir = TempDir("dataset");
  const std::vector<std::string> common{"dataset",     kDefault, "--episodes", "2",
                                        "--episode-s", "3",      "--seed",     "5"};
  const auto dataset = [&](const std::string& out, std::vector<std::string> extra,
                           const std::string& launcher = "") {
    std::vector<std::string> args = common;
    args.insert(args.end(), {"--out", dir + "/" + out});
    args.insert(args.end(), extra.begin(), extra.end());
    if (launcher.empty()) return RunCli(args);
    std::vector<std::string> argv{launcher,          "-np",   "2",   "--allow-run-as-root",
                                  "--oversubscribe", "--mca", "btl", "self,vader",
                                  UAVSIM_CLI};
    argv.insert(argv.end(), args.begin(), args.end());
    return RunProgram(argv);
  };
  const std::string data = dir + "/episodes.bin";
  const auto one = dataset("one.h5", {"--data", data});
  INFO(one.out << one.err);
  REQUIRE(one.exit_code == 0);
  CHECK_THAT(one.out, Catch::Contains("2 episodes of 3 s"));
  CHECK(Listing(dir) == std::set<std::string>{"one.h5", "episodes.bin"});  // no temporaries
  const std::string bytes = ReadFile(dir + "/one.h5");

  // Every field against the episodes the same run kept in --data.
  const std::vector<Episode> episodes = uavsim::pipeline::ReadEpisodes(data);
  REQUIRE(episodes.size() == 2);
  {
    const H5::H5File f(dir + "/one.h5", H5F_ACC_RDONLY);
    const H5::Group root = f.openGroup("/");
    const auto& I64 = H5::PredType::NATIVE_INT64;
    CHECK(NumberAttribute<std::int64_t>(root, "schema_version", I64) == 1);
    CHECK(NumberAttribute<std::uint64_t>(root, "seed", H5::PredType::NATIVE_UINT64) == 5);
    CHECK(NumberAttribute<std::int64_t>(root, "episodes", I64) == 2);
    CHECK(NumberAttribute<double>(root, "episode_s", H5::PredType::NATIVE_DOUBLE) == 3.0);
    CHECK(NumberAttribute<double>(root, "window_s", H5::PredType::NATIVE_DOUBLE) == 0.2);
    CHECK(NumberAttribute<std::int64_t>(root, "latent_dim", I64) == 0);
    CHECK(StringAttribute(root, "model").empty());
    CHECK(StringAttribute(root, "scenario_file") == kDefault);
    CHECK_FALSE(StringAttribute(root, "uavsim_version").empty());
    const auto scenario = uavsim::core::Json::parse(StringAttribute(root, "scenario"));
    CHECK(scenario["name"] == "default");
    CHECK(Strings(root.openAttribute("modalities")) ==
          std::vector<std::string>{"camera", "lidar", "radar"});
    CHECK_FALSE(f.nameExists("/episodes/000000/frames/latent"));

    // The nodes as the scenario lists them.
    const std::vector<std::string> ids = Strings(f.openDataSet("/nodes/id"));
    REQUIRE(ids.size() == scenario["nodes"].size());
    const auto modality = Read<std::uint8_t>(f, "/nodes/modality", H5::PredType::NATIVE_UINT8);
    const auto position = Read<double>(f, "/nodes/position_m", H5::PredType::NATIVE_DOUBLE);
    const auto rpy = Read<double>(f, "/nodes/rpy_deg", H5::PredType::NATIVE_DOUBLE);
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const auto& node = scenario["nodes"][i];
      CHECK(ids[i] == node["id"]);
      const std::string type = node["sensor"]["type"];
      CHECK(modality.v[i] == (type == "fisheye_stereo" ? 0 : type == "lidar" ? 1 : 2));
      for (int k = 0; k < 3; ++k) {
        CHECK(position.v[3 * i + k] == node["sensor"]["pose"]["position_m"][k].get<double>());
        CHECK(rpy.v[3 * i + k] == node["sensor"]["pose"]["rpy_deg"][k].get<double>());
      }
    }

    // The dtypes of the schema.
    CHECK(TypeOf(f, "/episodes/000000/camera/crop_left") ==
          std::make_pair(H5T_INTEGER, std::size_t{1}));
    CHECK(TypeOf(f, "/episodes/000000/lidar/points") == std::make_pair(H5T_FLOAT, std::size_t{4}));
    CHECK(TypeOf(f, "/episodes/000000/frames/t_arrival_s") ==
          std::make_pair(H5T_FLOAT, std::size_t{8}));
    // The crops are compressed one to a chunk.
    const H5::DSetCreatPropList crops =
        f.openDataSet("/episodes/000000/camera/crop_left").getCreatePlist();
    CHECK(crops.getLayout() == H5D_CHUNKED);
    CHECK(crops.getNfilters() == 2);  // shuffle, deflate

    std::size_t frames[3] = {0, 0, 0};
    for (std::size_t i = 0; i < episodes.size(); ++i) {
      CheckEpisode(f, i, episodes[i]);
      for (const Sample& s : episodes[i].samples) ++frames[static_cast<int>(s.modality)];
    }
    // The default scenario's three modalities all saw the target.
    CHECK(frames[0] > 0);
    CHECK(frames[1] > 0);
    CHECK(frames[2] > 0);
  }

  // The same file from episodes simulated two at a time, on two MPI ranks,
  // or read back from --data.
  const auto two = dataset("two.h5", {"--jobs", "2", "--quiet"});
  INFO(two.err);
  REQUIRE(two.exit_code == 0);
  CHECK(two.out.empty());
  CHECK(ReadFile(dir + "/two.h5") == bytes);
  const auto saved = dataset("saved.h5", {"--data", data, "--quiet"});
  REQUIRE(saved.exit_code == 0);
  CHECK(ReadFile(dir + "/saved.h5") == bytes);
  const std::string mpirun = FindOnPath("mpirun");
  if (mpirun.empty()) FAIL("mpirun is not on PATH (Debian: apt-get install openmpi-bin)");
  const auto ranks = dataset("mpi.h5", {"--quiet"}, mpirun);
  INFO("mpirun said: " << ranks.out << ranks.err);
  REQUIRE(ranks.exit_code == 0);
  CHECK(ReadFile(dir + "/mpi.h5") == bytes);
  // And cmp agrees (the file as a user compares it).
  CHECK(RunProgram({"/usr/bin/cmp", dir + "/one.h5", dir + "/mpi.h5"}).exit_code == 0);

  // An existing file is replaced only with --force.
  const auto again = dataset("one.h5", {"--data", data, "--quiet"});
  CHECK(again.exit_code == 2);
  CHECK(Lines(again.err) == 1);
  CHECK_THAT(again.err, Catch::Contains(dir + "/one.h5") && Catch::Contains("--force"));
  const auto forced = dataset("one.h5", {"--data", data, "--quiet", "--force"});
  REQUIRE(forced.exit_code == 0);
  CHECK(ReadFile(dir + "/one.h5") == bytes);

  // With a model: each frame's latent, the mean the node's encoder sends.
  const auto latent = dataset("latent.h5", {"--data", data, "--model", kModel, "--quiet"});
  INFO(latent.err);
  REQUIRE(latent.exit_code == 0);
  {
    const H5::H5File f(dir + "/latent.h5", H5F_ACC_RDONLY);
    const H5::Group root = f.openGroup("/");
    CHECK(NumberAttribute<std::int64_t>(root, "latent_dim", H5::PredType::NATIVE_INT64) == 16);
    CHECK_THAT(StringAttribute(root, "model"), Catch::Contains("models/default/model.json"));
    uavsim::pipeline::InitTorch(1, 5);
    const auto model = uavsim::pipeline::UavLocModelFiles::Load(kModel);
    for (std::size_t i = 0; i < episodes.size(); ++i) {
      char name[48];
      std::snprintf(name, sizeof name, "/episodes/%06zu/frames/latent", i);
      const auto z = Read<float>(f, name, H5::PredType::NATIVE_FLOAT);
      REQUIRE(z.dims == std::vector<hsize_t>{episodes[i].samples.size(), 16});
      for (std::size_t j = 0; j < episodes[i].samples.size(); ++j) {
        const Sample& s = episodes[i].samples[j];
        const auto& encoder = model->encoder(s.modality);
        const std::vector<float> mu =
            s.camera ? encoder.Encode(*s.camera) : encoder.Encode(*s.points);
        INFO("episode " << i << " frame " << j);
        CHECK(std::vector<float>(z.v.begin() + static_cast<std::ptrdiff_t>(16 * j),
                                 z.v.begin() + static_cast<std::ptrdiff_t>(16 * (j + 1))) == mu);
      }
      CheckEpisode(f, i, episodes[i]);  // the rest as without a model
    }
  }

  // h5py reads it: the shapes it sees, as this test does.
  const std::string python = PythonWithH5py();
  const std::string script =
      "import sys, h5py\n"
      "f = h5py.File(sys.argv[1], 'r')\n"
      "e = f['episodes/000001']\n"
      "print(f.attrs['seed'], f.attrs['latent_dim'], f.attrs['modalities'][2],"
      " list(f['nodes/id'].asstr()[:]))\n"
      "for k in ['window_truth_m', 'frames/t_arrival_s', 'frames/latent', 'camera/crop_left',"
      " 'lidar/points', 'radar/offsets']:\n"
      "    print(k, e[k].shape, e[k].dtype)\n";
  if (python.empty()) {
    WARN("python3 with h5py is not installed (scripts/setup installs python3-h5py): skipped");
    return;
  }
  const auto py = RunProgram({python, "-c", script, dir + "/latent.h5"});
  INFO(py.err);
  REQUIRE(py.exit_code == 0);
  const Episode& e = episodes[1];
  std::ostringstream want;
  want << "5 16 radar [";
  const std::vector<std::string> ids =
      Strings(H5::H5File(dir + "/latent.h5", H5F_ACC_RDONLY).openDataSet("/nodes/id"));
  for (std::size_t i = 0; i < ids.size(); ++i) want << (i ? ", '" : "'") << ids[i] << "'";
  const auto count = [&e](uavsim::core::Modality m) { return RowsOf(e, m).size(); };
  std::size_t lidar_points = 0;
  for (const Sample& s : e.samples)
    if (s.modality == uavsim::core::Modality::kLidar) lidar_points += s.points->count();
  want << "]\n"
       << "window_truth_m (" << e.window_truth.size() << ", 3) float64\n"
       << "frames/t_arrival_s (" << e.samples.size() << ",) float64\n"
       << "frames/latent (" << e.samples.size() << ", 16) float32\n"
       << "camera/crop_left (" << count(uavsim::core::Modality::kCamera) << ", 128, 128) uint8\n"
       << "lidar/points (" << lidar_points << ", 4) float32\n"
       << "radar/offsets (" << count(uavsim::core::Modality::kRadar) + 1 << ",) int64\n";
  CHECK(py.out == want.str());
}

TEST_CASE("DatasetFile: empty arrays have a zero first dimension, and h5py reads them",
          "[sim][dataset]") {
  const std::string dir = TempDir("dataset-empty");
  const std::string path = dir + "/empty.h5";
  uavsim::sim::DatasetHeader header;
  header.scenario = "{}";
  std::vector<Episode> episodes(1);
  episodes[0].label = "nothing seen";
  uavsim::sim::DatasetNode node;
  node.id = "cam1";
  uavsim::sim::WriteDatasetFile(path, header, {node}, episodes, {});
  const H5::H5File f(path, H5F_ACC_RDONLY);
  for (const char* set :
       {"window_truth_m", "frames/t_capture_s", "frames/truth_m", "camera/crop_left",
        "camera/eye_left_m", "lidar/points", "radar/points", "radar/sensor_position_m"}) {
    INFO(set);
    const auto a =
        Read<double>(f, std::string("/episodes/000000/") + set, H5::PredType::NATIVE_DOUBLE);
    REQUIRE_FALSE(a.dims.empty());
    CHECK(a.dims[0] == 0);
  }
  CHECK(Read<std::int64_t>(f, "/episodes/000000/lidar/offsets", H5::PredType::NATIVE_INT64).v ==
        std::vector<std::int64_t>{0});
  const std::string python = PythonWithH5py();
  if (python.empty()) {
    WARN("python3 with h5py is not installed (scripts/setup installs python3-h5py): skipped");
    return;
  }
  const auto py = RunProgram(
      {python, "-c",
       "import sys, h5py\n"
       "e = h5py.File(sys.argv[1], 'r')['episodes/000000']\n"
       "print(e['camera/crop_left'][:].shape, e['radar/points'][:].shape, e['lidar/offsets'][:])",
       path});
  INFO(py.err);
  CHECK(py.out == "(0, 128, 128) (0, 5) [0]\n");
}

TEST_CASE("DatasetFile: the same contents give the same bytes", "[sim][dataset]") {
  const std::string dir = TempDir("dataset-same");
  uavsim::sim::DatasetHeader header;
  header.scenario = "{\"name\": \"x\"}";
  std::vector<Episode> episodes(2);
  episodes[1].samples.resize(1);
  Sample& s = episodes[1].samples[0];
  s.modality = uavsim::core::Modality::kRadar;
  s.t_s = 0.25;
  s.fate = SampleFate::kLost;
  s.points.emplace();
  s.points->channels = 5;
  s.points->values = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  episodes[1].window_truth.push_back({1, 2, 3});
  uavsim::sim::DatasetNode node;
  node.id = "radar1";
  node.modality = uavsim::core::Modality::kRadar;
  uavsim::sim::WriteDatasetFile(dir + "/a.h5", header, {node}, episodes, {});
  uavsim::sim::WriteDatasetFile(dir + "/b.h5", header, {node}, episodes, {});
  CHECK(ReadFile(dir + "/a.h5") == ReadFile(dir + "/b.h5"));
  // A sample of a node the file does not list is refused, naming the file.
  episodes[1].samples[0].node = 1;
  CHECK_THROWS_WITH(uavsim::sim::WriteDatasetFile(dir + "/c.h5", header, {node}, episodes, {}),
                    Catch::Contains(dir + "/c.h5") && Catch::Contains("node 1"));
}

TEST_CASE("CLI: dataset refuses bad input with one line and exit 2, writing nothing",
          "[sim][dataset]") {
  const std::string dir = TempDir("dataset-bad");
  const std::string out = dir + "/out.h5";
  WriteFile(dir + "/existing.h5", "not mine");
  WriteFile(dir + "/a-file", "a file where a folder should be");
  const std::set<std::string> before = Listing(dir);
  struct Case {
    std::vector<std::string> args;
    std::vector<std::string> said;  // what the line must name
  };
  const std::string missing = dir + "/no-such-scenario.json";
  const std::vector<Case> cases{
      {{"dataset", missing, "--out", out}, {missing}},
      {{"dataset", kDefault}, {"--out"}},
      {{"dataset", kDefault, "--out", out, "--episodes", "0"}, {"--episodes"}},
      {{"dataset", kDefault, "--out", out, "--jobs", "x"}, {"--jobs", "'x'"}},
      {{"dataset", kDefault, "--out", out, "--bogus"}, {"--bogus"}},
      {{"dataset", kDefault, "--out", dir + "/existing.h5"}, {dir + "/existing.h5", "--force"}},
      {{"dataset", kDefault, "--out", dir}, {dir, "folder"}},
      // A model whose latents are not the scenario's size: the scenario's
      // file and pointer named.
      {{"dataset", kDefault, "--out", out, "--model", kModel, "--set", "/pipeline/latent_dim=8"},
       {kDefault, "/pipeline/latent_dim", "16"}},
      {{"dataset", kDefault, "--out", out, "--model", kModel, "--set", "/pipeline/window_s=0.25"},
       {kDefault, "/pipeline/window_s"}},
      {{"dataset", kDefault, "--out", out, "--model", dir + "/no-model"}, {dir + "/no-model"}},
      // An out folder that cannot be made (a file is in the way).
      {{"dataset", kDefault, "--out", dir + "/a-file/out.h5"}, {dir + "/a-file/out.h5"}},
  };
  for (const Case& c : cases) {
    std::string line;
    for (const std::string& a : c.args) line += " " + a;
    INFO("uavsim" << line);
    std::vector<std::string> args = c.args;
    args.push_back("--quiet");
    const auto r = RunCli(args);
    INFO(r.err);
    CHECK(r.exit_code == 2);
    CHECK(Lines(r.err) == 1);
    for (const std::string& s : c.said) CHECK_THAT(r.err, Catch::Contains(s));
    CHECK(Listing(dir) == before);  // no file, no temporary, no folder
    CHECK(ReadFile(dir + "/existing.h5") == "not mine");
  }
}

// Training data for UAVLoc as the simulator produces it (plain data, torch-
// free): per episode (one trajectory, one seed, one weather and loss draw)
// every pre-processed observation a sensing node produced, with the truth at
// its capture time and its fate on the uplink, and the truth at the end of
// every alignment window. Stage 1 (IB-CC) learns from the observations, stage
// 2 (fusion and Mamba) from the windows of on-time latents.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/node/observations.h"

namespace uavsim::pipeline {

// What became of a sample's message on the uplink (channel/edge_receiver.h:
// a window's deadline is its end plus the late allowance). The values are
// stored in episode files and in `uavsim dataset` files: do not renumber.
enum class SampleFate : std::uint8_t {
  kOnTime = 0,    // arrived by its window's deadline (on_time)
  kLate = 1,      // arrived after it (the edge treats it as missing)
  kLost = 2,      // never arrives (the uplink dropped it)
  kInFlight = 3,  // still on the uplink when the episode ended
  // An episode file of version 01 kept on_time only: a sample that was not
  // on time was late, lost or in flight, which it did not record.
  kUnknown = 255,
};
// "on_time", "late", "lost", "in_flight", "unknown".
const char* SampleFateName(SampleFate f);

// One node frame whose pre-processing found something to send.
struct Sample {
  Modality modality = Modality::kCamera;
  std::uint32_t node = 0;  // index of the node in its scenario
  double t_s = 0.0;        // capture time, simulated seconds
  bool on_time = false;    // arrived at the edge before its window's deadline
  // How the message fared, and when it arrived at the edge (simulated
  // seconds; NaN unless the fate is kOnTime or kLate, or when unknown).
  // on_time == (fate == SampleFate::kOnTime) for simulated samples.
  SampleFate fate = SampleFate::kInFlight;
  double t_arrival_s = std::numeric_limits<double>::quiet_NaN();
  // Target position at the observation's own time stamp (PointObservation::t_s,
  // CameraObservation::t_s; a LiDAR sweep's differs from t_s).
  Eigen::Vector3d truth_m = Eigen::Vector3d::Zero();
  std::optional<CameraObservation> camera;  // set for the camera
  std::optional<PointObservation> points;   // set for LiDAR and radar
};

// An episode's samples, shared between copies of the episode until one of
// them changes its own (copy on write): a split by frame puts one episode in
// all three parts without three copies of its crops (a full-size data set
// of 8 GB in memory would need 24). Reads through a const list never copy;
// a non-const begin(), end(), operator[], push_back, clear or resize makes
// this list's samples its own first. Not thread-safe for concurrent writers
// of copies that share samples.
class SampleList {
 public:
  using value_type = Sample;
  using const_iterator = std::vector<Sample>::const_iterator;
  using iterator = std::vector<Sample>::iterator;

  std::size_t size() const { return p_ ? p_->size() : 0; }
  bool empty() const { return size() == 0; }
  const Sample& operator[](std::size_t i) const { return (*p_)[i]; }
  const Sample& at(std::size_t i) const { return View().at(i); }
  const Sample& front() const { return View().front(); }
  const Sample& back() const { return View().back(); }
  const_iterator begin() const { return View().begin(); }
  const_iterator end() const { return View().end(); }

  Sample& operator[](std::size_t i) { return Own()[i]; }
  Sample& at(std::size_t i) { return Own().at(i); }
  Sample& front() { return Own().front(); }
  Sample& back() { return Own().back(); }
  iterator begin() { return Own().begin(); }
  iterator end() { return Own().end(); }
  void push_back(Sample s) { Own().push_back(std::move(s)); }
  void clear() { Own().clear(); }
  void resize(std::size_t n) { Own().resize(n); }
  void reserve(std::size_t n) { Own().reserve(n); }

  // Whether this list and `other` hold the same samples in memory.
  bool SharesWith(const SampleList& other) const { return p_ && p_ == other.p_; }

 private:
  const std::vector<Sample>& View() const;
  std::vector<Sample>& Own();
  std::shared_ptr<std::vector<Sample>> p_;
};

struct Episode {
  std::string label;  // what varied, for reports: "figure8 37 x 18 m, rain 4 mm/h, loss 19 %"
  // Its number in the episode set (EpisodeScenario's i, the HDF5 export's
  // /episodes/<i>); -1 unknown. Set by whoever reads or gathers the set;
  // not stored by dataset_io (the position in the file is the number).
  int index = -1;
  double window_s = 0.2;
  // The modalities whose nodes sent their data without pre-processing
  // (/pipeline/preprocess raw; bit m: Modality m), kRawUnknown for an
  // episode file that predates the record (version 01).
  static constexpr std::uint8_t kRawUnknown = 0xFF;
  std::uint8_t raw_modalities = 0;
  SampleList samples;                         // in capture order
  std::vector<Eigen::Vector3d> window_truth;  // [k - 1]: target position at k t^w
  // The windows whose truth the part of a Dataset holding this copy may use:
  // empty, every window (a split by trajectory); else [k - 1] is 1 for the
  // windows of this part (a split by frame). Stage 1 learns from the samples
  // captured in such windows only; stage 2's losses, its validation and the
  // held-out scores count such windows only. Not stored by dataset_io.
  std::vector<std::uint8_t> scored_windows;
  // Whether window k (1-based) is scored, as above.
  bool Scored(std::int64_t k) const {
    if (scored_windows.empty()) return true;
    return k >= 1 && k <= static_cast<std::int64_t>(scored_windows.size()) &&
           scored_windows[static_cast<std::size_t>(k - 1)] != 0;
  }
};

// How a Dataset was split into training, validation and test parts.
enum class DataSplit {
  // By trajectory (the default): each episode is its own trajectory and lies
  // in one part only, 70 / 15 / 15 % with at least one episode in each part
  // when there are three or more. Held-out scores are on unseen flights.
  kTrajectory,
  // By frame (the random frame split common in the literature): every
  // episode lies in every part, each of its windows drawn into one part
  // (70 / 15 / 15 %) and scored there only (Episode::scored_windows). A
  // test window's neighbours, 0.2 s away, were training labels; its inputs
  // were seen in training, unlabelled.
  kFrame,
};
const char* DataSplitName(DataSplit s);  // "trajectory", "frame"

// The weather an episode was simulated in, from its label (apps/train/train.cpp
// writes ", rain N mm/h" and ", fog N m"): "clear", "rain", "fog" or
// "rain+fog".
std::string WeatherOf(const Episode& e);

struct Dataset {
  std::vector<Episode> train, validation, test;
  DataSplit split = DataSplit::kTrajectory;
};

}  // namespace uavsim::pipeline

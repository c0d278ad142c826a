// `uavsim bench camera`: the camera node's work per frame, part by part.
#pragma once

#include <ostream>

namespace uavsim::sim {

// The default scenario's stereo camera node on one thread, milliseconds per
// stereo frame (both eyes):
//   capture   FisheyeStereo::Capture with the static cache (the run's
//             path), the same without sensor noise (the noise's share is
//             the difference) and without the cache (every ray cast);
//   pre-processing  CameraPreprocessor::Process over a second of frames of
//             the flight (30 frames after 10 s: detection on), then its
//             steps timed alone with the same OpenCV calls on the same
//             frames: the two rectifications (cv::remap, fixed-point maps),
//             MOG2 on the left eye, the closing, the labelling, the running
//             means (two dilations and masked accumulateWeighted).
// Google Benchmark times each by wall clock for at least 0.5 s; the fastest
// of three repetitions is kept (the machine may be shared). Writes a table
// to `out`: part, ms per frame, share of Process or of Capture; unless
// `quiet`, a line naming the camera and the frames first. Returns 0.
int BenchCamera(bool quiet, std::ostream& out);

}  // namespace uavsim::sim

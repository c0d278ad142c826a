#include "sensors/radar_processing_config.h"

#include <utility>
#include <vector>

#include "core/json_io.h"

namespace uavsim::sensors {

using core::Rule;

template <class V>
void Visit(V& v, RadarProcessingConfig& c) {
  v.Enum("angle_method", c.angle_method,
         {{"music", AngleMethod::kMusic},
          {"esprit", AngleMethod::kEsprit},
          {"beamscan", AngleMethod::kBeamscan}});
  v("clutter_removal", c.clutter_removal);
  const std::vector<std::pair<const char*, RadarWindow>> windows = {
      {"hann", RadarWindow::kHann},
      {"hamming", RadarWindow::kHamming},
      {"blackman", RadarWindow::kBlackman},
      {"rectangular", RadarWindow::kRectangular}};
  v.Enum("range_window", c.range_window, windows);
  v.Enum("doppler_window", c.doppler_window, windows);
  v("cfar_guard_range_cells", c.cfar_guard_range_cells, Rule::Range(0, 64));
  v("cfar_guard_doppler_cells", c.cfar_guard_doppler_cells, Rule::Range(0, 64));
  v("cfar_training_range_cells", c.cfar_training_range_cells, Rule::Range(1, 256));
  v("cfar_training_doppler_cells", c.cfar_training_doppler_cells, Rule::Range(1, 256));
  // Below 1e-12 the threshold solve meets the limits of double precision.
  v("cfar_pfa", c.cfar_pfa, Rule::Range(1e-12, 0.1));
  v("interpolate_peaks", c.interpolate_peaks);
  v("max_detections", c.max_detections, Rule::Range(1, 65536));
  v("snapshot_neighbourhood_cells", c.snapshot_neighbourhood_cells, Rule::Range(0, 4));
  v("forward_backward", c.forward_backward);
  v.Enum("source_count", c.source_count, {{"one", SourceCount::kOne}, {"mdl", SourceCount::kMdl}});
  v("max_sources", c.max_sources, Rule::Range(1, 8));
  v("music_grid_step_deg", c.music_grid_step_deg, Rule::Range(0.05, 10.0));
  v("beamscan_fft_size", c.beamscan_fft_size, Rule::Range(4, 1024));
}
UAVSIM_INSTANTIATE_VISIT(RadarProcessingConfig);

}  // namespace uavsim::sensors

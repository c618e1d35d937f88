/// \file The terminal table of a modal result (its files: output/modal_json.hpp).
#include <cstdio>
#include <string>
#include <vector>

#include "modal/modal.hpp"

namespace crackle::modal {
namespace {

std::string format(const char* pattern, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

}  // namespace

std::string modal_table(const ModalResult& result) {
  std::string text;
  int unpaired = 0;
  if (!result.pairs.empty()) {
    text += " mode  f_uncracked [Hz]      f_open [Hz]  open#    ratio      MAC  f_bilinear [Hz]\n";
    for (const ModePair& pair : result.pairs) {
      char line[200];
      std::snprintf(line, sizeof line, "%5d %17.6g %16.6g %6d %8.5f %8.4f %16.6g%s\n", pair.uncracked_mode + 1,
                    pair.f_uncracked_hz, pair.f_open_hz, pair.open_mode + 1, pair.ratio, pair.mac,
                    pair.f_bilinear_hz, pair.paired ? "" : "  unpaired");
      text += line;
      unpaired += !pair.paired;
    }
    if (unpaired > 0) {
      text += "(unpaired: MAC below " + format("%.1f", kPairingMac) +
              ", the open partner is not among the modes computed; raise modal.modes)\n";
    }
  } else {
    text += " mode";
    for (const VariantResult& variant : result.variants) {
      char header[64];
      std::snprintf(header, sizeof header, " %20s", (std::string("f_") + mesh::variant_name(variant.variant) + " [Hz]").c_str());
      text += header;
    }
    text += "\n";
    const int modes = result.variants.empty() ? 0 : result.variants.front().modes.n_modes();
    for (int mode = 0; mode < modes; ++mode) {
      text += format("%5.0f", mode + 1);
      for (const VariantResult& variant : result.variants) text += format(" %20.6g", variant.modes.frequencies_hz[mode]);
      text += "\n";
    }
  }
  for (const VariantResult& variant : result.variants) {
    if (variant.modes.n_rigid() > 0) {
      text += std::string("(") + mesh::variant_name(variant.variant) + ": " +
              std::to_string(variant.modes.n_rigid()) + " rigid-body modes not listed)\n";
    }
  }
  return text;
}

}  // namespace crackle::modal

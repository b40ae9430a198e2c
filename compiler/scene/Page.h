// The interactive page (`--target html`): one standalone HTML file that runs the webgl2 shader on a
// canvas with a slider per parameter component (grouped instance → transform / shape / material),
// reset, play/pause, mouse orbit (iMouse) and a frame-time readout. Works offline: no external
// resource, no library. Every string from the scene reaches the page as JSON with '<', '>' and '&'
// escaped and is shown through textContent, so no scene text can become markup or script.
#pragma once

#include <string>
#include <string_view>

namespace iqc {

// A JSON string literal for `text` that is also safe inside an HTML <script> element.
std::string json_string_for_html(std::string_view text);

// JSON text (already valid) made safe inside an HTML <script> element: '<', '>', '&', U+2028 and U+2029
// (which can only occur inside JSON strings) become \u escapes.
std::string json_for_html(std::string_view json);

// The page for a webgl2 shader and its --meta JSON. `live_reload` is extra script run at the end of the
// page's setup (iqc serve); empty for a standalone page.
std::string html_page(std::string_view webgl2_shader, std::string_view meta_json, std::string_view live_reload = {});

}  // namespace iqc

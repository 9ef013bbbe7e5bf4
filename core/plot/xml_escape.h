#pragma once
// Text that goes into XML or HTML (SVG labels, dashboard pages): escapes what would break
// the markup or an attribute.

#include <string>
#include <string_view>

namespace pnp::plot {

// & < > " ' as entities; everything else as it is.
std::string escape_xml(std::string_view text);

}  // namespace pnp::plot

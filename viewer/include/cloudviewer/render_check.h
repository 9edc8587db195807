// The check of a `view.render` entry against the viewer's parameter tables, for code that must not
// see the viewer's settings (cloudgen's preset reader: a preset whose view the viewer would refuse
// is refused when it is read, so `generate` never writes a file `cloudviewer` cannot open). One
// declaration, no other header: the tables live in cloudviewer_params (settings.h, atmosphere.h).
#pragma once
#include <string>

namespace cloudviewer {

/// Checks one KEY: VALUE of a `view.render` object as the viewer applies it (apply_setting:
/// render.KEY or KEY, atmosphere.KEY, motion.KEY; the same parsing and ranges). Returns "" when the
/// viewer accepts it, else what is wrong with the allowed values ("invalid value, allowed: a number
/// in [1, 8192]", "unknown key render.x (known: ...)").
std::string view_render_problem(const std::string& key, const std::string& value);

}  // namespace cloudviewer

// The fixed quantities of the nominal rig (MODEL.md, "Nominal model" table). The model check
// never fits these: they are geometry, supply and catalogue values that the rig engineer knows.
#pragma once

#include <numbers>

namespace leakmon::model {

struct RigConstants {
  double bore = 0.0381;                                              // D [m]
  double rod = 0.0254;                                               // d [m]
  double area = std::numbers::pi / 4.0 * (bore * bore - rod * rod);  // A [m^2]
  double stroke = 0.610;                                             // L [m]
  double dead_volume = 1e-5;                                         // V_dead [m^3] per side
  double line_volume = 6e-5;                                         // V_line [m^3] per side
  double supply_pressure = 17.2e6;                                   // ps [Pa]
  double tank_pressure = 0.1e6;                                      // pt [Pa]
  double spring = 80e3;                                              // K_s [N/m]
  double spool_tau = 2.5e-3;                                         // tau [s], nominal
  double command_full_scale = 10.0;                                  // u_max [V]
  double laminar_threshold = 2e5;                                    // dp_lin [Pa]
  double null_leakage = 5e-13;                                       // C_n [m^3/(s Pa)]
  double end_stop_stiffness = 1e7;                                   // [N/m]
  double end_stop_damping = 5e3;                                     // [N s/m]

  double half_volume() const { return area * stroke / 2.0 + dead_volume + line_volume; }
};

}  // namespace leakmon::model

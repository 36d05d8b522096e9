// The nominal parameter table of MODEL.md ("Nominal model"), SI units, member names as the
// symbols there. The calibratable ones (beta, Kv, m, b) and every other value may be overridden
// by a scenario; `nominal()` is the model as shipped.
#pragma once

#include <numbers>

namespace leakmon::sim {

struct Parameters {
  double D = 38.1e-3;       // bore [m] (from the paper)
  double d = 25.4e-3;       // rod diameter, double rod [m] (from the paper)
  double L = 0.610;         // stroke [m] (from the paper)
  double V_dead = 1e-5;     // dead volume per side [m^3]
  double V_line = 6e-5;     // valve-to-cylinder line volume per side [m^3]
  double ps = 17.2e6;       // supply pressure [Pa] (from the paper)
  double pt = 0.1e6;        // tank pressure [Pa]
  double beta = 700e6;      // effective bulk modulus [Pa]
  double m = 10.0;          // moving mass [kg]
  double b = 300.0;         // viscous friction [N s/m]
  double K_s = 80e3;        // load spring [N/m] (from the paper)
  double Kv = 3.39e-7;      // valve coefficient [m^3/(s sqrt(Pa))]
  double tau = 2.5e-3;      // spool time constant [s]
  double u_max = 10.0;      // valve command full scale [V]
  double dp_lin = 2e5;      // orifice laminar threshold [Pa]
  double C_n = 5e-13;       // valve null leakage per land [m^3/(s Pa)]
  double sigma_w = 0.0015;  // spool flow noise std. dev. (fraction of full travel)
  double tau_w = 1e-3;      // spool flow noise correlation time [s]
  double K_stop = 1e7;      // end-stop stiffness [N/m]
  double c_stop = 5e3;      // end-stop damping [N s/m]

  // Annulus area, both sides: pi/4 (D^2 - d^2).
  double A() const { return std::numbers::pi / 4.0 * (D * D - d * d); }
  // Chamber volume at mid-stroke: A L/2 + V_dead + V_line.
  double V0() const { return A() * L / 2.0 + V_dead + V_line; }

  static Parameters nominal() { return {}; }
};

}  // namespace leakmon::sim

// SPDX-License-Identifier: Apache-2.0
// Hydraulic plant model of the sprayer: what the papers' test benches are made of, simulated.
//
//   tank -> filter -> 24 V diaphragm pump -+-> proportional return valve -> tank
//                                          +-> spray line (hose + air chamber) -> pressure
//                                              sensor, pulse flow meter -> N solenoid valves
//                                              -> N nozzles
//
// Used by the closed-loop experiments (lab/experiments/), the sim tests and the simulated
// io backends (io/sim/, `weedsprayd --sim`). Pure and single-threaded: no clocks, no I/O; time
// only advances in step(). Not thread-safe: a caller sharing it between threads wraps it.
//
// Two sets of defaults: PlantParams{} is the ideal bench the papers' single-seed experiments
// ran on (one pressure node, smooth pump, linear meter, constant valves); every realism effect
// defaults to "off" there so those figures stay reproducible. realistic_plant_params()
// turns them all on at documented values; the --plants experiments draw machines around it
// (sim/plant/machine_draw.hpp). Each realistic value names its source, or says
// "invented" with the range the machine draws sweep.
//
// Units: SI unless the name says otherwise; pressures are gauge pressures in MPa, flows in
// L/min where the name says so. Every default documents where the value comes from (the parts
// the UGV paper names, or the datasheet class of such parts). Defaults are not tuned to make
// our controllers look good: valve delays, nozzle spread and meter error are the datasheet
// classes' typical values.
#pragma once

#include <array>
#include <cstdint>
#include <random>
#include <vector>

namespace weedspray::sim::plant {

inline constexpr int kMaxNozzles = 8;

struct PumpParams {
  // 24 V DC diaphragm pump (UGV paper: A42-24; class of 24 V agricultural diaphragm pumps:
  // 5-8 L/min open flow, 0.7-1.0 MPa shut-off). Linear pressure-flow curve between them.
  double open_flow_l_per_min = 8.0;
  double shutoff_pressure_mpa = 1.0;
  // Motor spin-up / spin-down time constant after the relay switches (small DC motor).
  double spin_time_constant_s = 0.15;
  // Pulsation: the outlet flow of an n-chamber single-acting diaphragm pump is the sum of n
  // half-sines 2 pi / n apart (each chamber discharges for half a turn of the wobble plate),
  // mean kept at the curve's flow. 0 = smooth. Realistic 3 (the 3-chamber wobble-plate pumps
  // of the A42-24 / Seaflo 42 class): the strokes overlap, so the flow ripples +4.7 % / -9.3 %
  // six times a revolution (2 x chambers x rpm / 60 Hz, ~180 Hz at 1800 rpm).
  int chambers = 0;
  // Shaft speed at nominal voltage and no load. Invented within the class (brushed 24 V motors
  // of such pumps run 1500-3000 rpm); machine draws sweep 1500-2500.
  double rated_rpm = 1800.0;
  // DC motor: speed (and flow) proportional to supply voltage (back-EMF ~ speed)...
  double nominal_supply_volts = 24.0;
  double supply_volts = 24.0;
  // ...and sagging with load torque (~ pressure): fraction of speed lost at shut-off pressure.
  // Invented (permanent-magnet motor droop of 15-30 % at stall torque); draws sweep 0.1-0.3.
  // It moves the pulsation frequency; the flow-pressure curve above already includes it.
  double load_speed_sag = 0.0;
  bool operator==(const PumpParams&) const = default;
};

struct ReturnValveParams {
  // Proportional return valve driven 0-10 V (UGV paper: FRSQT11F-16P). Opening is linear in
  // volts above a dead band; 10 V = fully open. Flow through it: opening * k * sqrt(P).
  double dead_band_volts = 0.5;
  double full_scale_volts = 10.0;
  // Flow coefficient when fully open [L/min per sqrt(MPa)]: able to bypass the pump's whole
  // output at low pressure (full open with all nozzles shut settles near 0.11 MPa).
  double k_l_per_min_sqrt_mpa = 20.0;
  // Proportional solenoid class: first-order lag from command to opening.
  double time_constant_s = 0.08;
  bool operator==(const ReturnValveParams&) const = default;
};

struct LineParams {
  // Compliance of the spray line: hose wall elasticity [L/MPa] (3 m of 10 mm braided PVC)...
  double hose_compliance_l_per_mpa = 0.005;
  // ...plus the diaphragm pump's outlet air chamber (pulsation damper), modelled as an
  // isothermal gas volume precharged at precharge_mpa (gauge). 0 disables it. Dampers are
  // precharged to 60-80 % of the working pressure: 0.14 MPa = 70 % of the UGV set-point.
  double air_chamber_volume_l = 0.1;
  double air_chamber_precharge_mpa = 0.14;
  // Below this pressure orifice flow is treated as laminar (linear in P) so the model stays
  // well-posed at P -> 0 (sqrt has infinite slope there).
  double laminar_below_mpa = 0.005;
  bool operator==(const LineParams&) const = default;
};

// The boom: hose from the manifold (sensor, meter) to the boom, then nozzle taps along it.
struct BoomParams {
  // Fluid inertance of the feed hose, rho l / A [MPa s^2 / L]. 0 = one pressure node (ideal
  // bench: no water hammer). Realistic 0.038: 3 m of 10 mm bore hose (1000 * 3 / 7.85e-5
  // Pa s^2/m^3); draws sweep hose length 2-5 m (0.025-0.064).
  double inertance_mpa_s2_per_l = 0.0;
  // Turbulent loss of the feed hose, dp = R q |q| [MPa / (L/s)^2]. Realistic 0.9: Darcy-
  // Weisbach, f = 0.037 (Re ~ 5500, smooth hose), 3 m of 10 mm at 2.6 L/min -> 1.7 kPa.
  double friction_mpa_per_l_per_s_sq = 0.0;
  // Compliance of the boom pipe and the hose's far half [L/MPa] (only with inertance > 0):
  // what the flow still arriving after the valves shut compresses -> the closing spike. Half of
  // LineParams' hose: with the inertance it gives the hose a wave speed of ~220 m/s, so the
  // spike of four valves shutting at once is of Joukowsky's rho a dv ~ 0.12 MPa.
  double boom_compliance_l_per_mpa = 0.0025;
  // Loss per boom section between adjacent taps, dp = r q^2 with q the flow still going on
  // along the boom (fed at nozzle 1's end) [MPa / (L/s)^2]. Realistic 0.3: 0.5 m of 10 mm
  // pipe (Darcy-Weisbach, 0.28 kPa at 2.6 L/min) plus a tee (K = 1.8, 0.27 kPa).
  double section_loss_mpa_per_l_per_s_sq = 0.0;
  // Each solenoid valve's own flow coefficient, in series with its nozzle [L/min per
  // sqrt(MPa)]. 0 = lossless valve. Realistic 7.9: Kv 0.15 m^3/h (2.5 L/min at 0.1 MPa), the
  // 2-2.5 mm orifice of direct-acting 2/2 valves of the Burkert 6013 class; 3 % of the
  // pressure is lost across it at 0.2 MPa.
  double valve_k_l_per_min_sqrt_mpa = 0.0;
  // Valve-to-valve spread of that coefficient, N(1, sigma) clipped at +-2.5 sigma. Invented
  // (orifice tolerance, seat wear); realistic 0.10.
  double valve_k_spread_sigma = 0.0;
  bool operator==(const BoomParams&) const = default;
};

struct NozzleParams {
  // Nozzle orifice coefficient [L/min per sqrt(MPa)]: 0.65 L/min at 0.2 MPa, 0.92 at 0.4
  // (TeeJet XR/11002 class; wheat paper nominal 0.615 L/min).
  double k_l_per_min_sqrt_mpa = 0.65 / 0.4472135955;
  // Manufacturing spread between nozzles: each nozzle's k is drawn from N(1, sigma), clipped
  // to +-2.5 sigma (ISO 5682: nozzles within +-5 % of rated flow).
  double k_spread_sigma = 0.02;
  // Solenoid valve response (small direct-acting 2/2 valves, e.g. Burkert 6013 class:
  // opening 10-20 ms, closing 20-40 ms): a dead time, then a linear travel.
  double open_delay_s = 0.015;
  double close_delay_s = 0.025;
  double open_travel_s = 0.004;
  double close_travel_s = 0.006;
  // Valve-to-valve spread of the delays, each drawn from N(1, sigma), clipped to +-2.5 sigma.
  double delay_spread_sigma = 0.10;
  // Valve-to-valve spread of the spool travel times (same law). 0 = all equal (ideal bench).
  // Invented (spring and coil tolerance); realistic 0.15.
  double travel_spread_sigma = 0.0;
  // Each valve's delays drift linearly at a rate drawn from N(0, sigma) [fraction per hour]
  // (coil heating, seal swelling). Invented; realistic 0.05, draws sweep 0-0.1.
  double delay_drift_per_hour_sigma = 0.0;
  bool operator==(const NozzleParams&) const = default;
};

struct PressureSensorParams {
  // 4-20 mA pressure transmitter (UGV paper: CKHTP-01), 0..full_scale gauge.
  double full_scale_mpa = 1.0;
  // I/V stage: shunt resistor so 20 mA -> 3.3 V (SPEC §4: 4-20 mA -> 0-3.3 V -> ADC).
  double shunt_ohms = 165.0;
  // White noise on the voltage after the I/V stage (transmitter 0.25 % FS class + wiring).
  double noise_volts_sigma = 0.002;
  // Transmitter response time constant.
  double time_constant_s = 0.002;
  // Calibration error of this transmitter against its label (the controller converts by the
  // label): zero offset as a fraction of the 16 mA span, span error as a fraction of the
  // reading, and the offset drifting at drift_per_hour [fraction of span per hour of plant
  // time]. Class 0.25-0.5 % FS transmitters: offset within +-0.5 % of span, span within +-1 %
  // (datasheet accuracy classes); the ideal bench has none.
  double offset_fraction = 0.0;
  double span_error = 0.0;
  double drift_per_hour = 0.0;
  bool operator==(const PressureSensorParams&) const = default;
};

struct FlowMeterParams {
  // Pulse flow meter in the spray line (UGV paper: LWGY turbine meter, 8500 pulses/L).
  double nominal_pulses_per_l = 8500.0;
  // The real meter differs from its label: true pulses/L = nominal * (1 + k_factor_error).
  // +2 %: LWGY class accuracy is +-1 % of reading inside its range, worse near its low end,
  // where a 4-nozzle boom at low duty runs. The catch-test calibration exists to remove this.
  double k_factor_error = 0.02;
  // Turbine meters under-read at low flow (bearing drag): true K x (1 - e exp(-q / knee)).
  // 0 = linear (ideal bench). Realistic e = 0.15, knee 0.25 L/min: invented in shape, sized so
  // the error is 1 % at 0.67 L/min, the low end of the LWGY-4 range (0.04 m^3/h) where its
  // +-1 % of reading stops applying; one nozzle at 25 % duty is below it.
  double low_flow_error = 0.0;
  double low_flow_knee_l_per_min = 0.25;
  // Pulse-edge jitter as a fraction of one pulse period (rotor blade spacing, pick-up
  // threshold noise), uniform +-. Invented; realistic 0.3.
  double pulse_jitter = 0.0;
  bool operator==(const FlowMeterParams&) const = default;
};

struct WheelParams {
  // Hall wheel sensor (UGV paper: JK8002D) on a toothed wheel: pulses per metre travelled.
  // Label value (e.g. 20 magnets on a 1 m circumference wheel)...
  double nominal_pulses_per_m = 20.0;
  // ...and the tyre's real rolling circumference differs by this fraction (load, slip).
  double circumference_error = 0.0;
  // Slip: the sensing wheel turns (1 + slip) times the ground distance (> 0 driven wheel
  // spinning, < 0 trailed wheel skidding). ASABE D497: 5-15 % for driven wheels on tilled soil;
  // a ground wheel runs -3..+5 % (invented); 0 = ideal.
  double slip = 0.0;
  bool operator==(const WheelParams&) const = default;
};

struct TankParams {
  double capacity_l = 20.0;
  double initial_level_l = 20.0;
  // Pump flow fades linearly to zero as the level drops below this (it starts drawing air).
  double suction_loss_below_l = 0.3;
  bool operator==(const TankParams&) const = default;
};

struct PlantParams {
  int nozzle_count = 4;
  PumpParams pump;
  ReturnValveParams return_valve;
  LineParams line;
  BoomParams boom;
  NozzleParams nozzle;
  PressureSensorParams pressure_sensor;
  FlowMeterParams flow_meter;
  WheelParams wheel;
  TankParams tank;
  // Fixed integration step; step(dt) sub-steps at this size (10 kHz).
  double integration_step_s = 1e-4;
  bool operator==(const PlantParams&) const = default;
};

// Every realism effect on at its documented value (see each field above).
PlantParams realistic_plant_params();

// A valve's opening crossing 50 % (HydraulicPlant::record_valve_crossings).
struct ValveCrossing {
  int nozzle = 0;
  bool opened = false;  // upward (else it closed)
  double time_s = 0.0;
  double distance_m = 0.0;  // ground travelled by then
};

// Per-nozzle values drawn from the seed: the "true" machine the calibrations must find.
struct NozzleTruth {
  double k_l_per_min_sqrt_mpa = 0.0;
  double open_delay_s = 0.0;
  double close_delay_s = 0.0;
  double open_travel_s = 0.0;
  double close_travel_s = 0.0;
  double valve_k_l_per_min_sqrt_mpa = 0.0;  // 0 = lossless valve
  double delay_drift_per_hour = 0.0;        // fraction per hour
};

class HydraulicPlant {
 public:
  // Throws std::invalid_argument naming the parameter if params are out of range.
  HydraulicPlant(const PlantParams& params, std::uint64_t seed);

  // --- actuators (take effect at the current simulated time) ---
  void set_pump(bool on);
  void set_return_valve_volts(double volts);  // clamped to [0, 10]
  void set_valves(std::uint32_t mask);        // bit i = solenoid valve i energised
  void set_ground_speed(double m_per_s);
  double ground_speed_m_per_s() const { return speed_m_per_s_; }

  // Advance simulated time by dt_s (>= 0), sub-stepping at params.integration_step_s.
  void step(double dt_s);

  // --- true state ---
  double time_s() const { return time_s_; }
  double line_pressure_mpa() const { return pressure_mpa_; }  // at the manifold / sensor
  // At the boom's first tap (= line pressure without inertance).
  double boom_pressure_mpa() const { return inertance_on() ? boom_pressure_mpa_ : pressure_mpa_; }
  double pump_rpm() const;
  double pump_flow_l_per_min() const { return pump_flow_l_per_s_ * 60.0; }
  double return_flow_l_per_min() const { return return_flow_l_per_s_ * 60.0; }
  double total_nozzle_flow_l_per_min() const;
  double nozzle_flow_l_per_min(int i) const;
  double valve_opening(int i) const;  // 0 closed .. 1 open (true spool position)
  double return_valve_opening() const { return return_opening_; }
  double nozzle_delivered_l(int i) const;  // TRUE volume through nozzle i since start
  double total_delivered_l() const;
  double distance_m() const { return distance_m_; }
  // Truth for placement tests: when on, each valve's opening crossing 50 % is logged with the
  // distance travelled then (to the integration step), until taken. Off by default: a long
  // simulation would grow the log without bound.
  void record_valve_crossings(bool on);
  std::vector<ValveCrossing> take_valve_crossings();
  double tank_level_l() const { return tank_level_l_; }
  const NozzleTruth& nozzle_truth(int i) const;
  int nozzle_count() const { return params_.nozzle_count; }
  const PlantParams& params() const { return params_; }
  // Flow of nozzle i fully open at pressure p (true k, its valve in series, no wear or
  // blockage): the reference for "requested" volumes.
  double nozzle_full_open_flow_l_per_min(int i, double pressure_mpa) const;
  // ...as it is now: with its wear and blockage (what a change did to it).
  double nozzle_open_flow_now_l_per_min(int i, double pressure_mpa) const;

  // --- sensors, as the controller's inputs see them ---
  double sensor_current_ma() const;      // 4-20 mA loop current (0 if wire broken)
  double pressure_sensor_volts() const;  // after the I/V stage, with seeded noise
  std::uint64_t flow_meter_pulses() const { return flow_pulses_; }
  std::uint64_t wheel_pulses() const { return wheel_pulses_; }
  double true_meter_pulses_per_l() const;

  // --- fault injection (for alarm tests) ---
  void set_nozzle_blockage(int i, double fraction);  // 0 clear .. 1 fully blocked
  void set_valve_stuck_open(int i, bool stuck);      // opens whatever it is commanded
  void set_filter_blockage(double fraction);         // reduces pump flow by this fraction
  void set_sensor_wire_broken(bool broken);          // loop current 0 mA
  void set_sensor_shorted(bool shorted);             // loop current 24 mA
  void set_tank_level_l(double litres);

  // --- changes after calibration (machine variation, lab/experiments/machines.hpp) ---
  void set_nozzle_wear(int i, double fraction);  // orifice flow coefficient x (1 + fraction)
  void set_valve_ageing(int i, double factor);   // delays and travel x factor (>= 0.5)
  void set_meter_drift(double fraction);         // true K-factor x (1 + fraction)
  void set_supply_volts(double volts);           // pump motor supply
  void set_wheel_slip(double slip);              // see WheelParams::slip

 private:
  struct Valve {
    bool commanded = false;
    double position = 0.0;        // 0..1
    double motion_target = 0.0;   // where the spool is heading
    double motion_start_s = 0.0;  // when it starts moving (command time + dead time)
    // A valve commanded back while its spool is travelling keeps travelling toward the old
    // end until the new dead time is over (the coil's field takes that long to turn round),
    // then reverses from wherever it got to. coast_target = position: no such motion.
    double coast_target = 0.0;
    double delivered_l = 0.0;
    double blockage = 0.0;
    double wear = 0.0;
    double ageing = 1.0;
    double flow_l_per_s = 0.0;
    bool stuck_open = false;
  };

  bool inertance_on() const { return params_.boom.inertance_mpa_s2_per_l > 0.0; }
  double delay_scale(int i) const;  // ageing x drift of valve i at the current time
  double metered_pulses_per_l(double line_flow_l_per_s) const;

  void substep(double dt_s);
  double advance_valve(Valve& valve, double t0, double dt_s) const;
  double orifice_flow_l_per_s(double k_l_per_min, double pressure_mpa) const;
  double series_k(int i) const;  // nozzle (worn, blocked) and valve in series
  double line_compliance_l_per_mpa(double pressure_mpa) const;

  PlantParams params_;
  std::array<NozzleTruth, kMaxNozzles> truth_{};
  std::array<Valve, kMaxNozzles> valves_{};
  std::uint32_t valve_mask_ = 0;  // the last set_valves() command
  std::mt19937_64 rng_;
  std::normal_distribution<double> unit_normal_{0.0, 1.0};
  // Draws of the realism effects come from their own stream so the ideal bench's draws (and
  // figures) do not move.
  std::mt19937_64 realism_rng_;
  std::normal_distribution<double> realism_normal_{0.0, 1.0};

  double time_s_ = 0.0;
  double pressure_mpa_ = 0.0;
  double sensor_pressure_mpa_ = 0.0;  // transmitter output (lagged)
  double sensor_noise_volts_ = 0.0;   // drawn once per step()
  bool pump_on_ = false;
  double pump_speed_ = 0.0;  // 0..1
  double pump_flow_l_per_s_ = 0.0;
  double return_volts_ = 0.0;
  double return_opening_ = 0.0;
  double return_flow_l_per_s_ = 0.0;
  double speed_m_per_s_ = 0.0;
  double distance_m_ = 0.0;
  double boom_pressure_mpa_ = 0.0;
  double line_flow_l_per_s_ = 0.0;  // through the feed hose (inertance on)
  double pump_angle_rad_ = 0.0;
  double supply_volts_ = 24.0;
  double meter_drift_ = 0.0;
  bool record_crossings_ = false;
  std::vector<ValveCrossing> crossings_;
  double wheel_slip_ = 0.0;
  double meter_phase_ = 0.0;       // pulses accumulated (fractional)
  double next_pulse_at_ = 1.0;     // jittered threshold of the next pulse
  double wheel_distance_m_ = 0.0;  // as the sensing wheel rolls it (slip)
  double metered_l_ = 0.0;         // volume through the flow meter
  std::uint64_t flow_pulses_ = 0;
  std::uint64_t wheel_pulses_ = 0;
  double tank_level_l_ = 0.0;
  double filter_blockage_ = 0.0;
  bool wire_broken_ = false;
  bool shorted_ = false;
};

}  // namespace weedspray::sim::plant

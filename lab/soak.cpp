// SPDX-License-Identifier: Apache-2.0
#include "lab/soak.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <systemd/sd-bus.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "daemon/records/as_applied_reader.hpp"
#include "daemon/records/totals.hpp"

namespace weedspray::lab {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

constexpr const char* kBusName = "org.weedspray.Sprayer1";
constexpr const char* kPath = "/org/weedspray/Sprayer1";
constexpr const char* kInterface = "org.weedspray.Sprayer1";

// The run's configuration: the sim's sparse field images made worth spraying (as the D-Bus
// integration test does); speed follows the default varying profile; the ideal bench, since
// the totals are judged against the plant's true volume through the meter's gain, which only
// its meter (a pure gain) allows (a drawn machine's meter also under-reads at low flow: a fact
// about the meter, not about the records).
constexpr const char* kConfig =
    "[spray]\nmax_density = 0.05\ndecision_threshold = 0.005\n[sim]\nmachine = \"ideal\"\n";

struct FaultKind {
  const char* name;
  std::vector<std::string> inject;
  const char* alarm;
  bool fault_class;
  std::vector<std::string> repair;
  double alarm_within_s;
};

const std::vector<FaultKind>& fault_kinds() {
  static const std::vector<FaultKind> kinds = {
      {"sensor_open", {"sensor_open"}, "pressure_sensor_fault", true, {"sensor_ok"}, 3},
      {"sensor_short", {"sensor_short"}, "pressure_sensor_fault", true, {"sensor_ok"}, 3},
      {"camera_gone", {"camera_gone"}, "camera_lost", true, {"camera_back"}, 10},
      {"tank_silent", {"tank_silent"}, "modbus_silent", false, {"tank_ok"}, 15},
      {"valve_write_fail",
       {"valve_write_fail"},
       "output_write_failed",
       true,
       {"valve_write_ok"},
       3},
      // A refused pump write shows when the pump must change: a sensor fault asks for it off.
      {"pump_write_fail",
       {"pump_write_fail", "sensor_open"},
       "output_write_failed",
       true,
       {"pump_write_ok", "sensor_ok"},
       3},
  };
  return kinds;
}

std::string this_tool_dir() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : self.parent_path().string();
}

std::string find_daemon(const std::string& given) {
  if (!given.empty()) return given;
  const fs::path beside = fs::path(this_tool_dir()) / ".." / "daemon" / "weedsprayd";
  if (fs::exists(beside)) return beside.string();
  const fs::path installed = fs::path(this_tool_dir()) / "weedsprayd";
  if (fs::exists(installed)) return installed.string();
  return "weedsprayd";
}

// A private session bus: never the user's. Returns its address; pid in `pid`.
std::string start_private_bus(pid_t& pid) {
  FILE* out =
      ::popen("dbus-daemon --session --fork --nopidfile --print-address=1 --print-pid=1", "r");
  if (out == nullptr) throw std::runtime_error("cannot run dbus-daemon (package dbus)");
  char address[512] = {};
  char pid_text[32] = {};
  const bool ok = std::fgets(address, sizeof address, out) != nullptr &&
                  std::fgets(pid_text, sizeof pid_text, out) != nullptr;
  ::pclose(out);
  if (!ok) throw std::runtime_error("dbus-daemon printed no address");
  address[std::strcspn(address, "\n")] = '\0';
  pid = static_cast<pid_t>(std::atol(pid_text));
  return address;
}

pid_t spawn(const std::vector<std::string>& argv, const fs::path& log) {
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::dup2(fd, STDOUT_FILENO);
      ::dup2(fd, STDERR_FILENO);
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  return pid;
}

struct ProcSample {
  double rss_kb = 0;
  double cpu_ticks = 0;
};

ProcSample sample_process(pid_t pid) {
  ProcSample s;
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.starts_with("VmRSS:")) s.rss_kb = std::atof(line.c_str() + 6);
  }
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const std::size_t close = text.rfind(')');
  if (close != std::string::npos) {
    std::istringstream fields(text.substr(close + 2));
    std::string field;
    for (int i = 3; i <= 15 && fields >> field; ++i) {
      if (i == 14 || i == 15) s.cpu_ticks += std::atof(field.c_str());  // utime, stime
    }
  }
  return s;
}

class Bus {
 public:
  Bus() {
    const int r = sd_bus_open_user(&bus_);
    if (r < 0) throw std::runtime_error(std::string("session bus: ") + std::strerror(-r));
  }
  ~Bus() { sd_bus_flush_close_unref(bus_); }
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  std::string state() {
    char* value = nullptr;
    sd_bus_error error = SD_BUS_ERROR_NULL;
    const int r =
        sd_bus_get_property_string(bus_, kBusName, kPath, kInterface, "State", &error, &value);
    sd_bus_error_free(&error);
    if (r < 0) return {};
    std::string out(value);
    std::free(value);
    return out;
  }
  std::vector<std::string> alarms() {
    char** list = nullptr;
    sd_bus_error error = SD_BUS_ERROR_NULL;
    const int r =
        sd_bus_get_property_strv(bus_, kBusName, kPath, kInterface, "Alarms", &error, &list);
    sd_bus_error_free(&error);
    std::vector<std::string> out;
    if (r < 0 || list == nullptr) return out;
    for (char** p = list; *p != nullptr; ++p) {
      out.emplace_back(*p);
      std::free(*p);
    }
    std::free(list);
    return out;
  }
  bool all_duties_zero() {
    sd_bus_message* reply = nullptr;
    sd_bus_error error = SD_BUS_ERROR_NULL;
    int r =
        sd_bus_get_property(bus_, kBusName, kPath, kInterface, "NozzleDuty", &error, &reply, "ad");
    sd_bus_error_free(&error);
    if (r < 0) return false;
    const void* data = nullptr;
    std::size_t size = 0;
    r = sd_bus_message_read_array(reply, 'd', &data, &size);
    bool zero = r >= 0;
    for (std::size_t i = 0; zero && i < size / sizeof(double); ++i)
      zero = static_cast<const double*>(data)[i] == 0.0;
    sd_bus_message_unref(reply);
    return zero;
  }
  std::uint64_t overruns() {
    std::uint64_t value = 0;
    sd_bus_error error = SD_BUS_ERROR_NULL;
    sd_bus_get_property_trivial(bus_, kBusName, kPath, kInterface, "ControlOverruns", &error, 't',
                                &value);
    sd_bus_error_free(&error);
    return value;
  }
  // Returns "" on success, else the error's message.
  std::string call(const char* method, const char* arg = nullptr) {
    sd_bus_error error = SD_BUS_ERROR_NULL;
    const int r = arg == nullptr ? sd_bus_call_method(bus_, kBusName, kPath, kInterface, method,
                                                      &error, nullptr, "")
                                 : sd_bus_call_method(bus_, kBusName, kPath, kInterface, method,
                                                      &error, nullptr, "s", arg);
    std::string message = r < 0 ? (error.message ? error.message : std::strerror(-r)) : "";
    sd_bus_error_free(&error);
    return message;
  }

 private:
  sd_bus* bus_ = nullptr;
};

bool wait_for(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
  const auto until = Clock::now() + timeout;
  while (Clock::now() < until) {
    if (condition()) return true;
    std::this_thread::sleep_for(50ms);
  }
  return condition();
}

bool has(const std::vector<std::string>& list, const std::string& item) {
  return std::find(list.begin(), list.end(), item) != list.end();
}

// Back to spraying after an event: ClearAlarms, Start, and Spraying within 5 s.
bool resume_spraying(Bus& bus) {
  for (int attempt = 0; attempt < 3; ++attempt) {
    if (bus.state() == "Spraying") return true;
    bus.call("ClearAlarms");
    bus.call("Start");
    if (wait_for([&] { return bus.state() == "Spraying"; }, 5s)) return true;
  }
  return false;
}

std::uint64_t count_lines(const fs::path& file, const std::string& needle) {
  std::ifstream in(file);
  std::string line;
  std::uint64_t n = 0;
  while (std::getline(in, line)) n += line.find(needle) != std::string::npos;
  return n;
}

}  // namespace

double SoakReport::log_vs_totals_pct() const {
  return totals_volume_l > 0 ? 100.0 * (log_volume_l - totals_volume_l) / totals_volume_l : 0;
}

double SoakReport::totals_vs_metered_pct() const {
  return plant_metered_l > 0 ? 100.0 * (totals_volume_l - plant_metered_l) / plant_metered_l : 0;
}

double SoakReport::totals_vs_plant_pct() const {
  return plant_volume_l > 0
             ? 100.0 * (totals_volume_l / plant_meter_gain - plant_volume_l) / plant_volume_l
             : 0;
}

double SoakReport::raw_totals_vs_plant_pct() const {
  return plant_volume_l > 0 ? 100.0 * (totals_volume_l - plant_volume_l) / plant_volume_l : 0;
}

bool SoakReport::passed() const {
  if (!error.empty() || daemon_exit_status != 0 || totals_volume_l <= 0) return false;
  for (const auto& e : events) {
    if (!e.alarm_raised || !e.resumed) return false;
    if (e.expects_valves_closed && !e.valves_closed) return false;
  }
  return rss_growth_kb() <= 1024 && std::abs(log_vs_totals_pct()) <= 0.5 &&
         std::abs(totals_vs_metered_pct()) <= 0.5 && std::abs(totals_vs_plant_pct()) <= 0.5 &&
         damaged_lines == 0;
}

SoakReport run_soak(const SoakOptions& options) {
  SoakReport report;
  report.options = options;
  const fs::path dir =
      options.keep_dir.empty()
          ? fs::temp_directory_path() / ("weedspray-soak-" + std::to_string(::getpid()))
          : fs::path(options.keep_dir);
  fs::create_directories(dir / "state");
  const fs::path config = dir / "weedspray.toml";
  std::ofstream(config) << kConfig;

  pid_t bus_pid = -1;
  pid_t daemon_pid = -1;
  std::mt19937_64 random(options.seed);
  try {
    const std::string address = start_private_bus(bus_pid);
    ::setenv("DBUS_SESSION_BUS_ADDRESS", address.c_str(), 1);
    daemon_pid =
        spawn({find_daemon(options.daemon), "--sim", "--user", "--config", config.string(),
               "--state-dir", (dir / "state").string(), "--valve-state-file",
               (dir / "valves.txt").string(), "--sim-truth-file", (dir / "truth.txt").string(),
               "--timing-report", (dir / "timing.txt").string()},
              dir / "daemon.log");
    Bus bus;
    if (!wait_for([&] { return bus.state() == "Idle"; }, 30s))
      throw std::runtime_error("the daemon did not reach Idle in 30 s (see " +
                               (dir / "daemon.log").string() + ")");
    if (!resume_spraying(bus)) throw std::runtime_error("the daemon did not start spraying");

    const auto t0 = Clock::now();
    const auto elapsed_s = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
    const double end_s = options.minutes * 60.0;
    const double warmup_s = std::min(300.0, 0.1 * end_s);
    std::uniform_real_distribution<double> interval(0.5 * options.mean_event_interval_s,
                                                    1.5 * options.mean_event_interval_s);
    double next_event_s = interval(random);
    double next_sample_s = 0;
    ProcSample last = sample_process(daemon_pid);
    double last_sample_s = 0;
    const double ticks_per_s = static_cast<double>(::sysconf(_SC_CLK_TCK));
    std::size_t rotation = 0;  // every kind of event in turn, in a seeded random order
    std::vector<std::string> kinds;
    for (const auto& f : fault_kinds()) kinds.push_back(f.name);
    kinds.insert(kinds.end(), {"reload", "reload_broken", "start_stop_storm"});
    std::shuffle(kinds.begin(), kinds.end(), random);

    while (elapsed_s() < end_s) {
      if (::waitpid(daemon_pid, nullptr, WNOHANG) == daemon_pid) {
        daemon_pid = -1;
        throw std::runtime_error("the daemon exited during the soak (see daemon.log)");
      }
      const double t = elapsed_s();
      if (t >= next_sample_s) {
        const ProcSample now = sample_process(daemon_pid);
        SoakSample s;
        s.t_s = t;
        s.rss_kb = now.rss_kb;
        s.cpu_pct = t > last_sample_s ? 100.0 * (now.cpu_ticks - last.cpu_ticks) / ticks_per_s /
                                            (t - last_sample_s)
                                      : 0;
        report.samples.push_back(s);
        if (report.rss_after_warmup_kb == 0 && t >= warmup_s) report.rss_after_warmup_kb = s.rss_kb;
        last = now;
        last_sample_s = t;
        next_sample_s = t + 10;
      }
      if (t < next_event_s) {
        std::this_thread::sleep_for(200ms);
        continue;
      }
      next_event_s = t + interval(random);
      SoakEvent event;
      event.t_s = t;
      event.kind = kinds[rotation++ % kinds.size()];
      if (rotation % kinds.size() == 0) std::shuffle(kinds.begin(), kinds.end(), random);
      const auto fault = std::find_if(fault_kinds().begin(), fault_kinds().end(),
                                      [&](const FaultKind& f) { return event.kind == f.name; });
      if (fault != fault_kinds().end()) {
        event.expected_alarm = fault->alarm;
        event.expects_valves_closed = fault->fault_class;
        const auto injected = Clock::now();
        for (const auto& name : fault->inject) {
          const std::string error = bus.call("InjectSimFault", name.c_str());
          if (!error.empty()) event.note += name + ": " + error + "; ";
        }
        event.alarm_raised =
            wait_for([&] { return has(bus.alarms(), event.expected_alarm); },
                     std::chrono::milliseconds(static_cast<int>(fault->alarm_within_s * 1000)));
        if (event.alarm_raised)
          event.alarm_after_ms =
              std::chrono::duration<double, std::milli>(Clock::now() - injected).count();
        if (event.expects_valves_closed) {
          event.valves_closed =
              wait_for([&] { return bus.state() == "Fault" && bus.all_duties_zero(); }, 1000ms);
        }
        for (const auto& name : fault->repair) bus.call("InjectSimFault", name.c_str());
        std::this_thread::sleep_for(1500ms);  // the repaired condition clears
      } else if (event.kind == "reload") {
        ::kill(daemon_pid, SIGHUP);
        std::this_thread::sleep_for(1s);
        event.alarm_raised = bus.state() == "Spraying";  // kept spraying through the reload
      } else if (event.kind == "reload_broken") {
        std::ofstream(config) << "[spray]\nmax_density = \"broken\"\n";
        const std::string error = bus.call("ReloadConfig");
        std::ofstream(config) << kConfig;
        event.alarm_raised = !error.empty() && bus.state() == "Spraying";
        event.note = error.empty() ? "the broken file was accepted" : "refused: " + error;
      } else {  // start_stop_storm
        for (int i = 0; i < 40; ++i) bus.call(i % 2 == 0 ? "Stop" : "Start");
        event.alarm_raised = true;
      }
      event.resumed = resume_spraying(bus);
      report.events.push_back(event);
    }
    report.control_overruns = bus.overruns();
    bus.call("Stop");
    std::this_thread::sleep_for(1s);
  } catch (const std::exception& e) {
    report.error = e.what();
  }
  if (daemon_pid > 0) {
    ::kill(daemon_pid, SIGTERM);
    int status = 0;
    ::waitpid(daemon_pid, &status, 0);
    report.daemon_exit_status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  if (bus_pid > 0) ::kill(bus_pid, SIGTERM);

  for (const auto& s : report.samples) {
    report.rss_max_kb = std::max(report.rss_max_kb, s.rss_kb);
    report.cpu_mean_pct += s.cpu_pct / static_cast<double>(report.samples.size());
  }
  if (!report.samples.empty()) report.rss_end_kb = report.samples.back().rss_kb;
  if (report.rss_after_warmup_kb == 0) report.rss_after_warmup_kb = report.rss_end_kb;
  report.alarms_raised = count_lines(dir / "daemon.log", "alarm raised:");
  report.alarms_cleared = count_lines(dir / "daemon.log", "alarm cleared:");
  report.unexpected_control_overrun_alarms =
      count_lines(dir / "daemon.log", "alarm raised: control_overruns");
  try {
    const daemon::AsAppliedSummary log = daemon::read_as_applied_dir(dir / "state" / "as-applied");
    report.log_volume_l = log.volume_l;
    report.log_records = log.records;
    report.torn_lines = log.torn_tail_lines;
    report.damaged_lines = log.damaged_lines;
    report.totals_volume_l = daemon::load_totals(dir / "state" / "totals.toml").volume_l;
    std::ifstream truth(dir / "truth.txt");
    std::string line;
    while (std::getline(truth, line)) {
      if (line.starts_with("sprayed_l=")) report.plant_volume_l = std::atof(line.c_str() + 10);
      if (line.starts_with("metered_l=")) report.plant_metered_l = std::atof(line.c_str() + 10);
      if (line.starts_with("meter_gain=")) report.plant_meter_gain = std::atof(line.c_str() + 11);
    }
    std::ifstream timing(dir / "timing.txt");
    report.timing_report.assign(std::istreambuf_iterator<char>(timing),
                                std::istreambuf_iterator<char>());
    while (!report.timing_report.empty() && std::isspace(report.timing_report.back()))
      report.timing_report.pop_back();
  } catch (const std::exception& e) {
    if (report.error.empty()) report.error = e.what();
  }
  if (options.keep_dir.empty()) fs::remove_all(dir);
  return report;
}

}  // namespace weedspray::lab

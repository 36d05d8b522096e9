// A CPU wake-up latency request (Linux PM QoS, /dev/cpu_dma_latency), held for as long as the
// object lives. Without it an idle CPU may enter a deep idle state (or, in a VM, halt the vCPU
// and leave it to the hypervisor), and waking from there costs tens to hundreds of
// microseconds on every loop period: the acquisition loop would measure the idle-state exit,
// not its own latency. cyclictest makes the same request (0 us) unless run with --laptop.
#pragma once

#include <cstdint>
#include <string>

namespace leakmon::realtime {

class CpuLatencyRequest {
 public:
  static constexpr const char* kDevice = "/dev/cpu_dma_latency";

  CpuLatencyRequest() = default;  // no request
  // Asks that no CPU sleeps deeper than `max_wakeup_us` allows. Never throws: where the device
  // is missing or not writable the request is not held and warning() says why.
  CpuLatencyRequest(std::int32_t max_wakeup_us, const std::string& device = kDevice);
  CpuLatencyRequest(CpuLatencyRequest&& other) noexcept;
  CpuLatencyRequest& operator=(CpuLatencyRequest&& other) noexcept;
  CpuLatencyRequest(const CpuLatencyRequest&) = delete;
  CpuLatencyRequest& operator=(const CpuLatencyRequest&) = delete;
  ~CpuLatencyRequest();  // closing the file withdraws the request

  bool held() const { return fd_ >= 0; }
  const std::string& warning() const { return warning_; }

 private:
  int fd_ = -1;
  std::string warning_;
};

}  // namespace leakmon::realtime

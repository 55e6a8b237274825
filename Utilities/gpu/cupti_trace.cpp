// A minimal GPU timeline recorder for machines without Nsight Systems (the GPU machine has ncu and
// compute-sanitizer only): a CUDA injection library (CUDA_INJECTION64_PATH=libpbf_cupti_trace.so;
// the driver calls InitializeInjection at cuInit) that records, through CUPTI's activity API,
// every kernel (concurrent kind, so streams still overlap), memcpy and memset with its GPU start
// and end, stream and name, and the runtime calls that wait (names containing "Synchronize" or
// "Wait"). At exit it writes one CSV per process, PBF_TRACE_DIR/trace-<rank or pid>.csv:
//   kind,start_ns,end_ns,stream,name
// Utilities/gpu/timeline.py reads them. A development tool only: nothing in the product links it.
#include <cupti.h>

#include <cxxabi.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>

#include <unistd.h>

namespace
{

std::FILE* out = nullptr;
std::mutex outLock;
constexpr std::size_t kBufferBytes = 16u << 20;

void check(CUptiResult result, const char* what)
{
  if (result != CUPTI_SUCCESS)
  {
    const char* text = nullptr;
    cuptiGetResultString(result, &text);
    std::fprintf(stderr, "pbf_cupti_trace: %s: %s\n", what, text ? text : "?");
  }
}

std::string demangled(const char* name)
{
  int status = 0;
  char* text = abi::__cxa_demangle(name, nullptr, nullptr, &status);
  std::string result = status == 0 && text ? text : name;
  std::free(text);
  // Commas would split the CSV field.
  for (char& c : result)
  {
    c = c == ',' ? ';' : c;
  }
  return result;
}

void CUPTIAPI bufferRequested(std::uint8_t** buffer, std::size_t* size, std::size_t* maxRecords)
{
  *buffer = static_cast<std::uint8_t*>(std::aligned_alloc(8, kBufferBytes));
  *size = kBufferBytes;
  *maxRecords = 0;
}

void CUPTIAPI bufferCompleted(
  CUcontext, std::uint32_t, std::uint8_t* buffer, std::size_t, std::size_t valid)
{
  std::lock_guard<std::mutex> guard(outLock);
  CUpti_Activity* record = nullptr;
  while (out && cuptiActivityGetNextRecord(buffer, valid, &record) == CUPTI_SUCCESS)
  {
    switch (record->kind)
    {
      case CUPTI_ACTIVITY_KIND_CONCURRENT_KERNEL:
      case CUPTI_ACTIVITY_KIND_KERNEL:
      {
        const auto* k = reinterpret_cast<const CUpti_ActivityKernel10*>(record);
        std::fprintf(out, "kernel,%llu,%llu,%u,%s\n", static_cast<unsigned long long>(k->start),
          static_cast<unsigned long long>(k->end), k->streamId, demangled(k->name).c_str());
        break;
      }
      case CUPTI_ACTIVITY_KIND_MEMCPY:
      {
        const auto* m = reinterpret_cast<const CUpti_ActivityMemcpy6*>(record);
        const char* kind = m->copyKind == CUPTI_ACTIVITY_MEMCPY_KIND_HTOD ? "HtoD"
          : m->copyKind == CUPTI_ACTIVITY_MEMCPY_KIND_DTOH               ? "DtoH"
          : m->copyKind == CUPTI_ACTIVITY_MEMCPY_KIND_DTOD               ? "DtoD"
                                                                         : "other";
        std::fprintf(out, "memcpy,%llu,%llu,%u,memcpy %s %s\n",
          static_cast<unsigned long long>(m->start), static_cast<unsigned long long>(m->end),
          m->streamId, kind, m->bytes < 65536 ? "<64K" : ">=64K");
        break;
      }
      case CUPTI_ACTIVITY_KIND_MEMSET:
      {
        const auto* m = reinterpret_cast<const CUpti_ActivityMemset4*>(record);
        std::fprintf(out, "memset,%llu,%llu,%u,memset\n", static_cast<unsigned long long>(m->start),
          static_cast<unsigned long long>(m->end), m->streamId);
        break;
      }
      case CUPTI_ACTIVITY_KIND_RUNTIME:
      {
        const auto* a = reinterpret_cast<const CUpti_ActivityAPI*>(record);
        const char* name = nullptr;
        cuptiGetCallbackName(CUPTI_CB_DOMAIN_RUNTIME_API, a->cbid, &name);
        if (name && (std::strstr(name, "Synchronize") || std::strstr(name, "Wait")))
        {
          std::fprintf(out, "wait,%llu,%llu,0,%s\n", static_cast<unsigned long long>(a->start),
            static_cast<unsigned long long>(a->end), name);
        }
        break;
      }
      default:
        break;
    }
  }
  std::free(buffer);
}

// The runtime may tear the context down before atexit handlers run; flush before that too.
void CUPTIAPI onResource(void*, CUpti_CallbackDomain domain, CUpti_CallbackId id, const void*)
{
  if (domain == CUPTI_CB_DOMAIN_RESOURCE && id == CUPTI_CBID_RESOURCE_CONTEXT_DESTROY_STARTING)
  {
    check(cuptiActivityFlushAll(1), "cuptiActivityFlushAll");
  }
}

void finish()
{
  check(cuptiActivityFlushAll(1), "cuptiActivityFlushAll");
  std::lock_guard<std::mutex> guard(outLock);
  if (out)
  {
    std::fclose(out);
    out = nullptr;
  }
}

} // namespace

extern "C" int InitializeInjection()
{
  const char* dir = std::getenv("PBF_TRACE_DIR");
  const char* rank = std::getenv("OMPI_COMM_WORLD_RANK");
  const std::string path = std::string(dir ? dir : ".") + "/trace-" +
    (rank ? std::string(rank) : std::to_string(static_cast<long>(getpid()))) + ".csv";
  out = std::fopen(path.c_str(), "w");
  if (!out)
  {
    std::fprintf(stderr, "pbf_cupti_trace: cannot write %s\n", path.c_str());
    return 0;
  }
  std::fprintf(out, "kind,start_ns,end_ns,stream,name\n");
  check(cuptiActivityRegisterCallbacks(bufferRequested, bufferCompleted), "register callbacks");
  check(cuptiActivityEnable(CUPTI_ACTIVITY_KIND_CONCURRENT_KERNEL), "enable kernels");
  check(cuptiActivityEnable(CUPTI_ACTIVITY_KIND_MEMCPY), "enable memcpy");
  check(cuptiActivityEnable(CUPTI_ACTIVITY_KIND_MEMSET), "enable memset");
  check(cuptiActivityEnable(CUPTI_ACTIVITY_KIND_RUNTIME), "enable runtime");
  CUpti_SubscriberHandle subscriber;
  check(cuptiSubscribe(&subscriber, reinterpret_cast<CUpti_CallbackFunc>(onResource), nullptr),
    "subscribe");
  check(cuptiEnableCallback(1, subscriber, CUPTI_CB_DOMAIN_RESOURCE,
          CUPTI_CBID_RESOURCE_CONTEXT_DESTROY_STARTING),
    "enable the context callback");
  std::atexit(finish);
  return 1;
}

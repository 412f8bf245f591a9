#include "estimators/graph/robust_kernel.hpp"

#include "estimators/kind_names.hpp"

namespace sextant::graph {
namespace {
constexpr std::pair<RobustKernel, const char*> kKernels[] = {{RobustKernel::kNone, "none"},
                                                             {RobustKernel::kHuber, "huber"},
                                                             {RobustKernel::kCauchy, "cauchy"},
                                                             {RobustKernel::kDcs, "dcs"}};
}  // namespace

RobustKernel robust_kernel_from_name(const std::string& name) {
  return kind_from_name(kKernels, name, "robust kernel");
}
const char* robust_kernel_name(RobustKernel kernel) { return kind_name(kKernels, kernel); }
std::vector<std::string> robust_kernel_names() { return kind_names(kKernels); }

}  // namespace sextant::graph

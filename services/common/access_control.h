#pragma once
// Who may call what, enforced for every RPC a server answers (ours, health, reflection):
// an auth metadata processor runs before any handler, recognises the caller from its
// bearer token or client certificate (security/auth_policy.h) and allows the call only if
// the caller holds the class the RPC needs (security/rpc_access.h); otherwise the call
// ends UNAUTHENTICATED or PERMISSION_DENIED with a message naming the RPC and the class.
// An audit interceptor records every operator and robot call, allowed calls with their
// first request message and final status, to the JSON log and the store's audit trail.

#include <grpcpp/grpcpp.h>
#include <grpcpp/security/auth_metadata_processor.h>
#include <grpcpp/support/server_interceptor.h>

#include <memory>
#include <string>

#include "security/access_class.h"
#include "security/auth_policy.h"
#include "store/audit_trail.h"

namespace pnp::services {

// The AuthContext property under which an allowed call's principal is recorded.
inline constexpr const char* kPrincipalProperty = "pnp_principal";

// The AuthContext property holding each access class the allowed caller was granted.
inline constexpr const char* kClassProperty = "pnp_class";

// The AuthContext property holding each training role the allowed caller is bound to.
inline constexpr const char* kRoleProperty = "pnp_role";

// The caller's principal as the processor recorded it; empty without a policy.
std::string principal_of(const grpc::ServerContextBase& context);

// Whether the policy grants the caller `access_class`; false without a policy (check
// principal_of first: without a policy every caller may do everything).
bool caller_holds(const grpc::ServerContextBase& context, security::AccessClass access_class);

// Throws PERMISSION_DENIED naming `field` unless the caller may act for training `role`:
// no policy, a principal bound to no roles, or one whose "roles" list it.
void require_role(const grpc::ServerContextBase& context, std::string_view role,
                  std::string_view field);

// Refused operator and robot calls also go to `audit` (may be null; must outlive the server).
std::shared_ptr<grpc::AuthMetadataProcessor> make_policy_processor(
    std::shared_ptr<const security::AuthPolicy> policy, std::string service,
    store::AuditTrail* audit);

// `audit` may be null (JSON log only); it must outlive the server.
std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> make_audit_factory(
    std::string service, store::AuditTrail* audit);

}  // namespace pnp::services

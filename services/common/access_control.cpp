#include "services/common/access_control.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <google/protobuf/util/json_util.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>

#include "common/handover.h"
#include "security/rpc_access.h"
#include "services/common/server_runtime.h"
#include "services/common/status.h"

namespace pnp::services {
namespace {

namespace gx = grpc::experimental;

constexpr std::size_t kMaxAuditedRequest = 2048;

std::string text(const grpc::string_ref& s) {
  return {s.data(), s.size()};
}

std::int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string first_value(const grpc::AuthContext& context, const char* property) {
  const auto values = context.FindPropertyValues(property);
  return values.empty() ? std::string() : text(values.front());
}

security::PresentedCredentials presented(const grpc::AuthMetadataProcessor::InputMetadata& metadata,
                                         const grpc::AuthContext& context) {
  security::PresentedCredentials out;
  const auto header = metadata.find("authorization");
  if (header != metadata.end()) {
    const std::string value = text(header->second);
    constexpr std::string_view kBearer = "Bearer ";
    if (value.size() > kBearer.size() && value.starts_with(kBearer))
      out.bearer_token = value.substr(kBearer.size());
    else
      out.malformed_authorization = true;
  }
  // Set only for a certificate the TLS handshake verified against --tls-client-ca.
  out.cert_common_name = first_value(context, GRPC_X509_CN_PROPERTY_NAME);
  for (const auto& san : context.FindPropertyValues(GRPC_X509_SAN_PROPERTY_NAME))
    out.cert_sans.push_back(text(san));
  return out;
}

class PolicyProcessor final : public grpc::AuthMetadataProcessor {
 public:
  PolicyProcessor(std::shared_ptr<const security::AuthPolicy> policy, std::string service,
                  store::AuditTrail* audit)
      : policy_(std::move(policy)), service_(std::move(service)), audit_(audit) {}

  bool IsBlocking() const override { return false; }  // hashing and a table lookup

  grpc::Status Process(const InputMetadata& metadata, grpc::AuthContext* context,
                       OutputMetadata* consumed, OutputMetadata* /*response*/) override {
    const HandoverScope handover(handed_over_);
    const auto path_it = metadata.find(":path");
    const std::string rpc = path_it == metadata.end() ? std::string() : text(path_it->second);
    const security::RpcAccess* access = security::find_rpc_access(rpc);
    const auto decision =
        security::decide_access(*policy_, presented(metadata, *context), rpc,
                                access ? std::optional(access->requirement) : std::nullopt);
    // The token goes no further: handlers, interceptors and logs never see it.
    const auto header = metadata.find("authorization");
    if (header != metadata.end()) consumed->emplace(text(header->first), text(header->second));
    using Outcome = security::AccessDecision::Outcome;
    if (decision.outcome == Outcome::kAllowed) {
      context->AddProperty(kPrincipalProperty, decision.principal);
      for (const security::AccessClass c : decision.classes)
        context->AddProperty(kClassProperty, std::string(security::access_class_name(c)));
      for (const std::string& role : decision.roles) context->AddProperty(kRoleProperty, role);
      return grpc::Status::OK;
    }
    const bool unauthenticated = decision.outcome == Outcome::kUnauthenticated;
    const char* code = unauthenticated ? "UNAUTHENTICATED" : "PERMISSION_DENIED";
    log_event(service_, "access_denied",
              {{"rpc", rpc},
               {"principal", decision.principal},
               {"code", code},
               {"reason", decision.message}});
    // A refused attempt at an operator or robot call is as much the audit's business as an
    // allowed one (the request itself is not read: it never reaches the server).
    if (audit_ && access && access->audited) {
      store::AuditRecord r;
      r.ts_ms = now_ms();
      r.service = service_;
      r.principal = decision.principal;
      r.rpc = rpc;
      r.request = "{}";
      r.code = code;
      audit_->append(std::move(r));
    }
    return {
        unauthenticated ? grpc::StatusCode::UNAUTHENTICATED : grpc::StatusCode::PERMISSION_DENIED,
        decision.message};
  }

 private:
  std::shared_ptr<const security::AuthPolicy> policy_;
  std::string service_;
  store::AuditTrail* audit_;
  HandedOver handed_over_;  // last: gRPC calls and destroys it on its own threads
};

// A lease id is the capability to drive the arm, and more people read the audit than may
// drive it: every lease_id in a request, however deep, is recorded as "[redacted]".
void redact_capabilities(google::protobuf::Message& message) {
  using google::protobuf::FieldDescriptor;
  const auto* descriptor = message.GetDescriptor();
  const auto* reflection = message.GetReflection();
  for (int i = 0; i < descriptor->field_count(); ++i) {
    const FieldDescriptor* field = descriptor->field(i);
    if (field->cpp_type() == FieldDescriptor::CPPTYPE_STRING && !field->is_repeated() &&
        field->name() == "lease_id") {
      if (!reflection->GetString(message, field).empty())
        reflection->SetString(&message, field, "[redacted]");
    } else if (field->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE) {
      if (field->is_repeated()) {
        for (int j = 0; j < reflection->FieldSize(message, field); ++j)
          redact_capabilities(*reflection->MutableRepeatedMessage(&message, field, j));
      } else if (reflection->HasField(message, field)) {
        redact_capabilities(*reflection->MutableMessage(&message, field));
      }
    }
  }
}

std::string request_json(const void* message) {
  if (message == nullptr) return "{}";
  // Every pnp service is generated from .proto files: its messages are protobuf messages.
  const auto* received = static_cast<const google::protobuf::Message*>(message);
  const std::unique_ptr<google::protobuf::Message> proto(received->New());
  proto->CopyFrom(*received);
  redact_capabilities(*proto);
  std::string json;
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  if (!google::protobuf::util::MessageToJsonString(*proto, &json, options).ok()) return "{}";
  if (json.size() > kMaxAuditedRequest) json = json.substr(0, kMaxAuditedRequest) + "...";
  return json;
}

// One audited call: the first request message, then its final status.
class AuditInterceptor final : public gx::Interceptor {
 public:
  AuditInterceptor(gx::ServerRpcInfo* info, const std::string& service, store::AuditTrail* audit)
      : info_(info), service_(service), audit_(audit) {}

  void Intercept(gx::InterceptorBatchMethods* methods) override {
    {
      const HandoverScope handover(handed_over_);
      if (methods->QueryInterceptionHookPoint(gx::InterceptionHookPoints::POST_RECV_MESSAGE) &&
          !have_request_.exchange(true)) {
        std::lock_guard lock(mutex_);
        request_ = request_json(methods->GetRecvMessage());
      }
      if (methods->QueryInterceptionHookPoint(gx::InterceptionHookPoints::PRE_SEND_STATUS))
        record(methods->GetSendStatus().error_code());
    }
    methods->Proceed();  // last: the call may end, and this be destroyed, from here on
  }

 private:
  void record(grpc::StatusCode code) {
    const auto* context = info_->server_context();
    store::AuditRecord r;
    r.ts_ms = now_ms();
    r.service = service_;
    r.principal = principal_of(*context);
    r.peer = context->peer();
    r.rpc = info_->method();
    {
      std::lock_guard lock(mutex_);
      r.request = request_.empty() ? "{}" : request_;
    }
    r.code = std::string(status_code_name(code));
    log_event(service_, "audit",
              {{"principal", r.principal},
               {"peer", r.peer},
               {"rpc", r.rpc},
               {"request", r.request},
               {"code", r.code}});
    if (audit_) audit_->append(std::move(r));
  }

  gx::ServerRpcInfo* info_;
  const std::string& service_;
  store::AuditTrail* audit_;
  std::atomic<bool> have_request_{false};
  std::mutex mutex_;
  std::string request_;
  HandedOver handed_over_;  // last: gRPC calls and destroys it on its own threads
};

class AuditFactory final : public gx::ServerInterceptorFactoryInterface {
 public:
  AuditFactory(std::string service, store::AuditTrail* audit)
      : service_(std::move(service)), audit_(audit) {}

  gx::Interceptor* CreateServerInterceptor(gx::ServerRpcInfo* info) override {
    const security::RpcAccess* access =
        info->method() ? security::find_rpc_access(info->method()) : nullptr;
    if (access == nullptr || !access->audited) return nullptr;  // not audited: no interceptor
    return std::make_unique<AuditInterceptor>(info, service_, audit_).release();
  }

 private:
  std::string service_;
  store::AuditTrail* audit_;
};

}  // namespace

std::string principal_of(const grpc::ServerContextBase& context) {
  const auto auth = context.auth_context();
  return auth ? first_value(*auth, kPrincipalProperty) : std::string();
}

bool caller_holds(const grpc::ServerContextBase& context, security::AccessClass access_class) {
  const auto auth = context.auth_context();
  if (!auth) return false;
  const std::string_view wanted = security::access_class_name(access_class);
  for (const auto& value : auth->FindPropertyValues(kClassProperty))
    if (std::string_view(value.data(), value.size()) == wanted) return true;
  return false;
}

void require_role(const grpc::ServerContextBase& context, std::string_view role,
                  std::string_view field) {
  const auto auth = context.auth_context();
  if (!auth) return;
  const auto bound = auth->FindPropertyValues(kRoleProperty);
  if (bound.empty()) return;
  std::string listed;
  for (const auto& value : bound) {
    const std::string_view name(value.data(), value.size());
    if (name == role) return;
    listed += (listed.empty() ? "" : ", ") + std::string(name);
  }
  throw Error(ErrorCode::kPermissionDenied, std::string(field) + ": principal \"" +
                                                principal_of(context) + "\" acts for the roles " +
                                                listed + " only (its policy's \"roles\"), not \"" +
                                                std::string(role) + "\"");
}

std::shared_ptr<grpc::AuthMetadataProcessor> make_policy_processor(
    std::shared_ptr<const security::AuthPolicy> policy, std::string service,
    store::AuditTrail* audit) {
  return std::make_shared<PolicyProcessor>(std::move(policy), std::move(service), audit);
}

std::unique_ptr<gx::ServerInterceptorFactoryInterface> make_audit_factory(
    std::string service, store::AuditTrail* audit) {
  return std::make_unique<AuditFactory>(std::move(service), audit);
}

}  // namespace pnp::services

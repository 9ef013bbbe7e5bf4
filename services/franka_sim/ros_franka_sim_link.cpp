// Built as C++17 (ROS 1's headers): see ros_franka_sim_link.h.
#include "services/franka_sim/ros_franka_sim_link.h"

#include <actionlib/server/simple_action_server.h>
#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/Float64.h>
#include <std_msgs/String.h>
#include <std_msgs/UInt64.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "franka_gripper/GraspAction.h"
#include "franka_gripper/MoveAction.h"
#include "franka_msgs/ErrorRecoveryAction.h"
#include "franka_msgs/FrankaState.h"
#include "services/franka_ros/franka_errors.h"

namespace pnp::services {
namespace {

template <typename Array, typename Source>
void copy_into(Array& to, const Source& from) {
  std::copy(from.begin(), from.end(), to.begin());
}

void fill_pose(geometry_msgs::Pose& out, const geometry::Pose& pose) {
  out.position.x = pose.position_m.x();
  out.position.y = pose.position_m.y();
  out.position.z = pose.position_m.z();
  out.orientation.w = pose.orientation.w();
  out.orientation.x = pose.orientation.x();
  out.orientation.y = pose.orientation.y();
  out.orientation.z = pose.orientation.z();
}

}  // namespace

struct RosFrankaSimLink::Impl {
  Impl(const FrankaSimTopics& t, FrankaSimInputs in)
      : topics(t),
        inputs(std::move(in)),
        move(
            node, topics.gripper + "/move",
            [this](const franka_gripper::MoveGoalConstPtr& goal) {
              franka_gripper::MoveResult result;
              result.success = inputs.on_move(goal->width);
              if (!result.success) result.error = "width out of range";
              finish(move, result);
            },
            false),
        grasp(
            node, topics.gripper + "/grasp",
            [this](const franka_gripper::GraspGoalConstPtr& goal) {
              franka_gripper::GraspResult result;
              result.success = inputs.on_grasp(goal->width);
              if (!result.success) result.error = "width out of range";
              finish(grasp, result);
            },
            false),
        recovery(
            node, topics.error_recovery,
            [this](const franka_msgs::ErrorRecoveryGoalConstPtr&) {
              inputs.on_error_recovery();
              recovery.setSucceeded(franka_msgs::ErrorRecoveryResult());
            },
            false) {}

  template <typename Server, typename Result>
  static void finish(Server& server, const Result& result) {
    if (result.success) {
      server.setSucceeded(result);
    } else {
      server.setAborted(result, result.error);
    }
  }

  FrankaSimTopics topics;
  FrankaSimInputs inputs;
  ros::NodeHandle node;
  actionlib::SimpleActionServer<franka_gripper::MoveAction> move;
  actionlib::SimpleActionServer<franka_gripper::GraspAction> grasp;
  actionlib::SimpleActionServer<franka_msgs::ErrorRecoveryAction> recovery;
  ros::Publisher state, arm_joints, finger_joints, object;
  ros::Subscriber equilibrium, inject_reflex, reset_scene, stall_state, stall_tracker;
  std::uint32_t sequence = 0;
  ros::AsyncSpinner spinner{2};
};

RosFrankaSimLink::RosFrankaSimLink(const FrankaSimTopics& topics, FrankaSimInputs inputs)
    : impl_(std::make_unique<Impl>(topics, std::move(inputs))) {
  Impl& i = *impl_;
  i.state = i.node.advertise<franka_msgs::FrankaState>(topics.state, 1);
  i.arm_joints = i.node.advertise<sensor_msgs::JointState>(topics.arm_joints, 1);
  i.finger_joints = i.node.advertise<sensor_msgs::JointState>(topics.finger_joints, 1);
  i.object = i.node.advertise<geometry_msgs::PoseStamped>(topics.object_pose, 1);
  const auto no_delay = ros::TransportHints().tcpNoDelay();
  i.equilibrium = i.node.subscribe<geometry_msgs::PoseStamped>(
      topics.equilibrium_pose, 1,
      [&i](const geometry_msgs::PoseStampedConstPtr& msg) {
        if (msg->header.frame_id != i.topics.base_frame) return;  // the controller ignores it
        const auto& p = msg->pose.position;
        const auto& q = msg->pose.orientation;
        const std::chrono::system_clock::time_point stamp(
            std::chrono::duration_cast<std::chrono::system_clock::duration>(
                std::chrono::nanoseconds(msg->header.stamp.toNSec())));
        i.inputs.on_equilibrium(
            {Eigen::Vector3d(p.x, p.y, p.z), Eigen::Quaterniond(q.w, q.x, q.y, q.z)}, stamp);
      },
      ros::VoidConstPtr(), no_delay);
  i.inject_reflex = i.node.subscribe<std_msgs::String>(
      topics.control + "/inject_reflex", 10, [&i](const std_msgs::StringConstPtr& msg) {
        franka_msgs::Errors known;  // only franka_msgs' own error names
        if (set_error_flag(known, msg->data)) i.inputs.on_inject_reflex(msg->data);
      });
  i.reset_scene = i.node.subscribe<std_msgs::UInt64>(
      topics.control + "/reset_scene", 10,
      [&i](const std_msgs::UInt64ConstPtr& msg) { i.inputs.on_reset_scene(msg->data); });
  const auto stall = [&i](const std::string& name, std::function<void(double)>& on_stall) {
    return i.node.subscribe<std_msgs::Float64>(
        i.topics.control + "/" + name, 10, [&on_stall](const std_msgs::Float64ConstPtr& msg) {
          if (std::isfinite(msg->data) && msg->data >= 0 && msg->data <= kMaxStall_s)
            on_stall(msg->data);
        });
  };
  i.stall_state = stall("stall_state", i.inputs.on_stall_state);
  i.stall_tracker = stall("stall_tracker", i.inputs.on_stall_tracker);
  i.move.start();
  i.grasp.start();
  i.recovery.start();
  i.spinner.start();
}

RosFrankaSimLink::~RosFrankaSimLink() {
  stop_callbacks();
}

void RosFrankaSimLink::stop_callbacks() {
  impl_->spinner.stop();
  impl_->equilibrium.shutdown();
  impl_->inject_reflex.shutdown();
  impl_->reset_scene.shutdown();
  impl_->stall_state.shutdown();
  impl_->stall_tracker.shutdown();
  impl_->move.shutdown();
  impl_->grasp.shutdown();
  impl_->recovery.shutdown();
}

void RosFrankaSimLink::publish_state(const FrankaSimReport& report) {
  Impl& i = *impl_;
  franka_msgs::FrankaState msg;
  msg.header.seq = ++i.sequence;
  msg.header.stamp = ros::Time::now();
  msg.header.frame_id = i.topics.base_frame;
  copy_into(msg.O_T_EE, report.O_T_EE);
  copy_into(msg.O_T_EE_d, report.O_T_EE_d);
  copy_into(msg.O_T_EE_c, report.O_T_EE_d);
  copy_into(msg.F_T_EE, report.F_T_EE);
  copy_into(msg.q, report.q);
  copy_into(msg.dq, report.dq);
  copy_into(msg.tau_J, report.tau_J);
  msg.time = report.time_s;
  msg.control_command_success_rate = 1.0;
  msg.robot_mode = report.robot_mode;
  for (const auto& name : report.current_errors) set_error_flag(msg.current_errors, name);
  i.state.publish(msg);

  sensor_msgs::JointState joints;
  joints.header = msg.header;
  for (int j = 1; j <= 7; ++j) joints.name.push_back("panda_joint" + std::to_string(j));
  joints.position.assign(report.q.begin(), report.q.end());
  joints.velocity.assign(report.dq.begin(), report.dq.end());
  joints.effort.assign(report.tau_J.begin(), report.tau_J.end());
  i.arm_joints.publish(joints);
}

void RosFrankaSimLink::publish_fingers(double finger_gap_m) {
  sensor_msgs::JointState fingers;
  fingers.header.stamp = ros::Time::now();
  fingers.name = {"panda_finger_joint1", "panda_finger_joint2"};
  fingers.position = {finger_gap_m / 2, finger_gap_m / 2};
  impl_->finger_joints.publish(fingers);
}

void RosFrankaSimLink::publish_object(const geometry::Pose& object_base) {
  geometry_msgs::PoseStamped msg;
  msg.header.stamp = ros::Time::now();
  msg.header.frame_id = impl_->topics.base_frame;
  fill_pose(msg.pose, object_base);
  impl_->object.publish(msg);
}

}  // namespace pnp::services

// Built as C++17 (ROS 1's headers): see ros_franka_link.h.
#include "services/franka_bridge/ros_franka_link.h"

#include <actionlib/client/simple_action_client.h>
#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <set>
#include <utility>

#include "franka_gripper/GraspAction.h"
#include "franka_gripper/MoveAction.h"
#include "franka_msgs/ErrorRecoveryAction.h"
#include "franka_msgs/FrankaState.h"

namespace pnp::services {
namespace {

// The names of the Errors flags that are set, as franka_msgs spells them.
std::vector<std::string> set_errors(const franka_msgs::Errors& e) {
  std::vector<std::string> names;
  const auto add = [&](bool set, const char* name) {
    if (set) names.emplace_back(name);
  };
  add(e.joint_position_limits_violation, "joint_position_limits_violation");
  add(e.cartesian_position_limits_violation, "cartesian_position_limits_violation");
  add(e.self_collision_avoidance_violation, "self_collision_avoidance_violation");
  add(e.joint_velocity_violation, "joint_velocity_violation");
  add(e.cartesian_velocity_violation, "cartesian_velocity_violation");
  add(e.force_control_safety_violation, "force_control_safety_violation");
  add(e.joint_reflex, "joint_reflex");
  add(e.cartesian_reflex, "cartesian_reflex");
  add(e.max_goal_pose_deviation_violation, "max_goal_pose_deviation_violation");
  add(e.max_path_pose_deviation_violation, "max_path_pose_deviation_violation");
  add(e.cartesian_velocity_profile_safety_violation, "cartesian_velocity_profile_safety_violation");
  add(e.joint_position_motion_generator_start_pose_invalid,
      "joint_position_motion_generator_start_pose_invalid");
  add(e.joint_motion_generator_position_limits_violation,
      "joint_motion_generator_position_limits_violation");
  add(e.joint_motion_generator_velocity_limits_violation,
      "joint_motion_generator_velocity_limits_violation");
  add(e.joint_motion_generator_velocity_discontinuity,
      "joint_motion_generator_velocity_discontinuity");
  add(e.joint_motion_generator_acceleration_discontinuity,
      "joint_motion_generator_acceleration_discontinuity");
  add(e.cartesian_position_motion_generator_start_pose_invalid,
      "cartesian_position_motion_generator_start_pose_invalid");
  add(e.cartesian_motion_generator_elbow_limit_violation,
      "cartesian_motion_generator_elbow_limit_violation");
  add(e.cartesian_motion_generator_velocity_limits_violation,
      "cartesian_motion_generator_velocity_limits_violation");
  add(e.cartesian_motion_generator_velocity_discontinuity,
      "cartesian_motion_generator_velocity_discontinuity");
  add(e.cartesian_motion_generator_acceleration_discontinuity,
      "cartesian_motion_generator_acceleration_discontinuity");
  add(e.cartesian_motion_generator_elbow_sign_inconsistent,
      "cartesian_motion_generator_elbow_sign_inconsistent");
  add(e.cartesian_motion_generator_start_elbow_invalid,
      "cartesian_motion_generator_start_elbow_invalid");
  add(e.cartesian_motion_generator_joint_position_limits_violation,
      "cartesian_motion_generator_joint_position_limits_violation");
  add(e.cartesian_motion_generator_joint_velocity_limits_violation,
      "cartesian_motion_generator_joint_velocity_limits_violation");
  add(e.cartesian_motion_generator_joint_velocity_discontinuity,
      "cartesian_motion_generator_joint_velocity_discontinuity");
  add(e.cartesian_motion_generator_joint_acceleration_discontinuity,
      "cartesian_motion_generator_joint_acceleration_discontinuity");
  add(e.cartesian_position_motion_generator_invalid_frame,
      "cartesian_position_motion_generator_invalid_frame");
  add(e.force_controller_desired_force_tolerance_violation,
      "force_controller_desired_force_tolerance_violation");
  add(e.controller_torque_discontinuity, "controller_torque_discontinuity");
  add(e.start_elbow_sign_inconsistent, "start_elbow_sign_inconsistent");
  add(e.communication_constraints_violation, "communication_constraints_violation");
  add(e.power_limit_violation, "power_limit_violation");
  add(e.joint_p2p_insufficient_torque_for_planning, "joint_p2p_insufficient_torque_for_planning");
  add(e.tau_j_range_violation, "tau_j_range_violation");
  add(e.instability_detected, "instability_detected");
  add(e.joint_move_in_wrong_direction, "joint_move_in_wrong_direction");
  add(e.cartesian_spline_motion_generator_violation, "cartesian_spline_motion_generator_violation");
  add(e.joint_via_motion_generator_planning_joint_limit_violation,
      "joint_via_motion_generator_planning_joint_limit_violation");
  add(e.base_acceleration_initialization_timeout, "base_acceleration_initialization_timeout");
  add(e.base_acceleration_invalid_reading, "base_acceleration_invalid_reading");
  return names;
}

// When a message was measured, on this process's steady clock: its arrival, less how old
// its stamp says it was (a tracker's latency counts against its freshness).
robot::SteadyTime measured_at(const ros::Time& stamp) {
  const auto arrived = std::chrono::steady_clock::now();
  if (stamp.isZero()) return arrived;
  const double age_s = std::max(0.0, (ros::Time::now() - stamp).toSec());
  return arrived - std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                       std::chrono::duration<double>(age_s));
}

}  // namespace

void init_ros_node(int& argc, char** argv, const std::string& node_name) {
  ros::init(argc, argv, node_name, ros::init_options::NoSigintHandler);
}

bool ros_master_reachable() {
  return ros::master::check();
}

void shutdown_ros_node() {
  ros::shutdown();
}

struct RosFrankaLink::Impl {
  Impl(const FrankaTopics& t, FrankaInputs in)
      : topics(t),
        inputs(std::move(in)),
        move(topics.gripper + "/move", false),
        grasp(topics.gripper + "/grasp", false),
        recovery(topics.error_recovery, false) {}

  void refuse_once(const std::string& topic, const std::string& why) {
    std::lock_guard<std::mutex> lock(refused_mutex);
    if (refused.insert(topic + why).second && inputs.on_refused) inputs.on_refused(topic, why);
  }

  void on_state(const franka_msgs::FrankaState& msg) {
    robot::FrankaStateSample s;
    s.received = measured_at(msg.header.stamp);
    std::copy(msg.O_T_EE.begin(), msg.O_T_EE.end(), s.O_T_EE.begin());
    std::copy(msg.F_T_EE.begin(), msg.F_T_EE.end(), s.F_T_EE.begin());
    std::copy(msg.q.begin(), msg.q.end(), s.q.begin());
    s.robot_mode = msg.robot_mode;
    s.current_errors = set_errors(msg.current_errors);
    inputs.on_state(s);
  }

  void on_fingers(const sensor_msgs::JointState& msg) {
    double width = 0;
    int found = 0;
    for (std::size_t i = 0; i < msg.name.size() && i < msg.position.size(); ++i) {
      if (msg.name[i] == topics.finger_joint_1 || msg.name[i] == topics.finger_joint_2) {
        width += msg.position[i];
        ++found;
      }
    }
    if (found != 2) {
      refuse_once(topics.finger_joints,
                  "no positions for " + topics.finger_joint_1 + " and " + topics.finger_joint_2);
      return;
    }
    inputs.on_gripper_width(width);
  }

  void on_object(const geometry_msgs::PoseStamped& msg) {
    if (msg.header.frame_id != topics.base_frame) {
      refuse_once(topics.object_pose, "frame_id \"" + msg.header.frame_id + "\", expected \"" +
                                          topics.base_frame + "\"");
      return;
    }
    const auto& p = msg.pose.position;
    const auto& q = msg.pose.orientation;
    const geometry::Pose pose{Eigen::Vector3d(p.x, p.y, p.z),
                              Eigen::Quaterniond(q.w, q.x, q.y, q.z)};
    if (!geometry::is_finite(pose) || std::abs(pose.orientation.norm() - 1.0) > 1e-3) {
      refuse_once(topics.object_pose, "a pose that is not finite or not a unit quaternion");
      return;
    }
    inputs.on_object({measured_at(msg.header.stamp), pose});
  }

  FrankaTopics topics;
  FrankaInputs inputs;
  ros::NodeHandle node;
  ros::Publisher equilibrium;
  ros::Subscriber state, fingers, object;
  actionlib::SimpleActionClient<franka_gripper::MoveAction> move;
  actionlib::SimpleActionClient<franka_gripper::GraspAction> grasp;
  actionlib::SimpleActionClient<franka_msgs::ErrorRecoveryAction> recovery;
  std::uint32_t sequence = 0;
  std::mutex refused_mutex;
  std::set<std::string> refused;  // guarded by refused_mutex
  ros::AsyncSpinner spinner{1};
};

RosFrankaLink::RosFrankaLink(const FrankaTopics& topics, FrankaInputs inputs)
    : impl_(std::make_unique<Impl>(topics, std::move(inputs))) {
  Impl& i = *impl_;
  // Equilibrium poses are only worth their newest: a queue of one.
  i.equilibrium = i.node.advertise<geometry_msgs::PoseStamped>(topics.equilibrium_pose, 1);
  const auto no_delay = ros::TransportHints().tcpNoDelay();
  i.state = i.node.subscribe(topics.state, 1, &Impl::on_state, &i, no_delay);
  i.fingers = i.node.subscribe(topics.finger_joints, 1, &Impl::on_fingers, &i, no_delay);
  i.object = i.node.subscribe(topics.object_pose, 1, &Impl::on_object, &i, no_delay);
  i.spinner.start();
}

RosFrankaLink::~RosFrankaLink() {
  stop_callbacks();
}

void RosFrankaLink::stop_callbacks() {
  impl_->spinner.stop();
  impl_->state.shutdown();
  impl_->fingers.shutdown();
  impl_->object.shutdown();
}

void RosFrankaLink::send_equilibrium_pose(const geometry::Pose& ee_base) {
  geometry_msgs::PoseStamped msg;
  msg.header.seq = ++impl_->sequence;
  msg.header.stamp = ros::Time::now();
  msg.header.frame_id = impl_->topics.base_frame;
  msg.pose.position.x = ee_base.position_m.x();
  msg.pose.position.y = ee_base.position_m.y();
  msg.pose.position.z = ee_base.position_m.z();
  msg.pose.orientation.w = ee_base.orientation.w();
  msg.pose.orientation.x = ee_base.orientation.x();
  msg.pose.orientation.y = ee_base.orientation.y();
  msg.pose.orientation.z = ee_base.orientation.z();
  impl_->equilibrium.publish(msg);
}

void RosFrankaLink::send_gripper_move(double width_m, double speed_m_per_s) {
  franka_gripper::MoveGoal goal;
  goal.width = width_m;
  goal.speed = speed_m_per_s;
  impl_->move.sendGoal(goal);  // a newer goal preempts the one before
}

void RosFrankaLink::send_gripper_grasp(double width_m, double epsilon_inner_m,
                                       double epsilon_outer_m, double speed_m_per_s,
                                       double force_n) {
  franka_gripper::GraspGoal goal;
  goal.width = width_m;
  goal.epsilon.inner = epsilon_inner_m;
  goal.epsilon.outer = epsilon_outer_m;
  goal.speed = speed_m_per_s;
  goal.force = force_n;
  impl_->grasp.sendGoal(goal);
}

void RosFrankaLink::send_error_recovery() {
  impl_->recovery.sendGoal(franka_msgs::ErrorRecoveryGoal());
}

int RosFrankaLink::equilibrium_subscribers() const {
  return static_cast<int>(impl_->equilibrium.getNumSubscribers());
}

}  // namespace pnp::services

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
#include "services/franka_ros/franka_errors.h"

namespace pnp::services {
namespace {

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

struct RosFrankaLink::Impl {
  Impl(const FrankaTopics& t, FrankaInputs in)
      : topics(t),
        inputs(std::move(in)),
        move(topics.gripper + "/move", false),
        grasp(topics.gripper + "/grasp", false),
        recovery(topics.error_recovery, false) {}

  // Once per kind of problem and topic; at most kMaxRefusalKinds kinds are remembered (a
  // publisher inventing frame names cannot grow the set), later new ones are not logged.
  void refuse_once(const std::string& topic, const std::string& why) {
    static constexpr std::size_t kMaxRefusalKinds = 64;
    std::lock_guard<std::mutex> lock(refused_mutex);
    if (refused.size() >= kMaxRefusalKinds) return;
    if (refused.insert(topic + why).second && inputs.on_refused) inputs.on_refused(topic, why);
  }

  void on_state(const franka_msgs::FrankaState& msg) {
    robot::FrankaStateSample s;
    s.received = measured_at(msg.header.stamp);
    std::copy(msg.O_T_EE.begin(), msg.O_T_EE.end(), s.O_T_EE.begin());
    std::copy(msg.F_T_EE.begin(), msg.F_T_EE.end(), s.F_T_EE.begin());
    std::copy(msg.q.begin(), msg.q.end(), s.q.begin());
    s.robot_mode = msg.robot_mode;
    s.current_errors = set_error_names(msg.current_errors);
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

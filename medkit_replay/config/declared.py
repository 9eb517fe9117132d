"""The parameters each node the replay models declares at each upstream release, as data.

From upstream's ``declare_parameter`` calls (and the names it reads undeclared); checked against
an upstream checkout by tests/config/declared_upstream.py. A name ending in ``.*`` is a prefix.
"""

from __future__ import annotations

from typing import Final

ROS_PARAMETERS: Final = frozenset(
    {
        "use_sim_time",  # rclcpp's TimeSource, every node
        "start_type_description_service",  # rclcpp from Jazzy on, every node
        "qos_overrides.*",  # rclcpp's QoS overrides (/parameter_events and opted-in topics)
    }
)
"""ROS 2's own parameters, declared by rclcpp on every node at every release."""

_REPLAY: Final = frozenset(
    {
        "upstream_release",  # config/release.py
        "enable_log_bridge",  # config/replay_options.py
        "action_sources.*",  # config/replay_options.py: action name -> action server node
    }
)
"""The replay's own node ``medkit_replay`` (not a ROS node: no ROS parameters)."""

# -- bdcc4ed0 (0.6.0) ---------------------------------------------------------------------------

# src/ros2_medkit_fault_reporter/src/fault_reporter.cpp:40-50, declared on the node that holds
# the reporter (the three bridges), each only when not yet declared.
_LOCAL_FILTER_060: Final = (
    "fault_reporter.local_filtering.enabled",
    "fault_reporter.local_filtering.default_threshold",
    "fault_reporter.local_filtering.default_window_sec",
    "fault_reporter.local_filtering.bypass_severity",
)

_FAULT_MANAGER_060: Final = frozenset(
    {
        # src/ros2_medkit_fault_manager/src/fault_manager_node.cpp at bdcc4ed0
        "storage_type",  # :74
        "database_path",  # :75
        "confirmation_threshold",  # :77
        "healing_enabled",  # :87
        "healing_threshold",  # :88
        "auto_confirm_after_sec",  # :97
        "snapshots.recapture_cooldown_sec",  # :104
        "snapshots.capture_pool_size",  # :114
        "snapshots.capture_queue_depth",  # :121
        "snapshots.capture_queue_full_policy",  # :128
        "snapshots.max_per_fault",  # :145
        "entity_thresholds.config_file",  # :170
        "correlation.cleanup_interval_sec",  # :274, only when a correlation engine exists
        "snapshots.enabled",  # :786
        "snapshots.background_capture",  # :787
        "snapshots.timeout_sec",  # :790
        "snapshots.max_message_size",  # :798
        "snapshots.default_topics",  # :808
        "snapshots.config_file",  # :811
        "snapshots.rosbag.enabled",  # :817; the rest of snapshots.rosbag.* only when true
        "snapshots.rosbag.duration_sec",  # :819
        "snapshots.rosbag.duration_after_sec",  # :826
        "snapshots.rosbag.topics",  # :833
        "snapshots.rosbag.include_topics",  # :835
        "snapshots.rosbag.exclude_topics",  # :837
        "snapshots.rosbag.exclude_sensor_topics",  # :838
        "snapshots.rosbag.qos_match",  # :839
        "snapshots.rosbag.lazy_start",  # :841
        "snapshots.rosbag.format",  # :842
        "snapshots.rosbag.storage_path",  # :843
        "snapshots.rosbag.max_bag_size_mb",  # :845
        "snapshots.rosbag.max_total_storage_mb",  # :852
        "snapshots.rosbag.max_buffer_mb",  # :859
        "snapshots.rosbag.auto_cleanup",  # :866
        "correlation.config_file",  # :943
    }
)

_DIAGNOSTIC_BRIDGE_060: Final = frozenset(
    {
        # src/ros2_medkit_diagnostic_bridge/src/diagnostic_bridge_node.cpp at bdcc4ed0
        "diagnostics_topic",  # :38
        "auto_generate_codes",  # :39
        "name_to_code.*",  # :44, read undeclared from the parameter overrides
        *_LOCAL_FILTER_060,
    }
)

_ACTION_STATUS_BRIDGE_060: Final = frozenset(
    {
        # src/ros2_medkit_action_status_bridge/src/action_status_bridge_node.cpp at bdcc4ed0
        "aborted_severity",  # :99
        "canceled_is_fault",  # :108
        "heal_on_succeeded",  # :109
        "rescan_period_sec",  # :110
        "code_prefix",  # :116
        "exclude_actions",  # :122
        "include_only_actions",  # :124
        "dedup_capacity",  # :126
        *_LOCAL_FILTER_060,  # enabled pre-declared off at :143
    }
)

_LOG_BRIDGE_060: Final = frozenset(
    {
        # src/ros2_medkit_log_bridge/src/log_bridge_node.cpp at bdcc4ed0
        "rosout_topic",  # :64
        "severity_floor",  # :68
        "code_prefix",  # :77
        "exclude_nodes",  # :81
        "include_only_nodes",  # :82
        "max_tracked_nodes",  # :83
        "report_cooldown_sec",  # :87
        "exclude_medkit_stack",  # :91
        *_LOCAL_FILTER_060,
    }
)

# -- 505bc2d5 (0.7.0; #591 on top declares nothing) ---------------------------------------------

# src/ros2_medkit_fault_reporter/src/fault_reporter.cpp:80-92 at 505bc2d5: the same four.
_LOCAL_FILTER_070: Final = _LOCAL_FILTER_060

_FAULT_MANAGER_070: Final = frozenset(
    {
        # src/ros2_medkit_fault_manager/src/fault_manager_node.cpp at 505bc2d5
        "storage_type",  # :105
        "database_path",  # :106
        "confirmation_threshold",  # :108
        "healing_enabled",  # :118
        "healing_threshold",  # :119
        "auto_confirm_after_sec",  # :128
        "snapshots.recapture_cooldown_sec",  # :135
        "snapshots.capture_pool_size",  # :145
        "snapshots.capture_queue_depth",  # :152
        "snapshots.capture_queue_full_policy",  # :159
        "snapshots.retain_on_clear",  # :181
        "snapshots.max_per_fault",  # :183
        "near_miss.max_per_fault",  # :195
        "entity_thresholds.config_file",  # :264
        "correlation.cleanup_interval_sec",  # :408, only when a correlation engine exists
        "audit_log.enabled",  # :513
        "audit_log.transitions",  # :517
        "audit_log.retention_max_records",  # :525
        "audit_log.fail_closed",  # :537
        "audit_log.database_path",  # :540
        "snapshots.enabled",  # :1140
        "snapshots.background_capture",  # :1141
        "snapshots.timeout_sec",  # :1144
        "snapshots.max_message_size",  # :1152
        "snapshots.default_topics",  # :1164
        "snapshots.entity_default",  # :1170
        "snapshots.config_file",  # :1173
        "snapshots.rosbag.enabled",  # :1179; the rest of snapshots.rosbag.* only when true
        "snapshots.rosbag.duration_sec",  # :1181
        "snapshots.rosbag.duration_after_sec",  # :1188
        "snapshots.rosbag.topics",  # :1195
        "snapshots.rosbag.include_topics",  # :1197
        "snapshots.rosbag.exclude_topics",  # :1199
        "snapshots.rosbag.exclude_sensor_topics",  # :1200
        "snapshots.rosbag.qos_match",  # :1201
        "snapshots.rosbag.lazy_start",  # :1203
        "snapshots.rosbag.format",  # :1204
        "snapshots.rosbag.storage_path",  # :1205
        "snapshots.rosbag.max_bag_size_mb",  # :1207
        "snapshots.rosbag.max_total_storage_mb",  # :1214
        "snapshots.rosbag.max_buffer_mb",  # :1221
        "snapshots.rosbag.max_bags_per_fault",  # :1234
        "snapshots.rosbag.auto_cleanup",  # :1241
        "correlation.config_file",  # :1318
    }
)

_DIAGNOSTIC_BRIDGE_070: Final = frozenset(
    {
        # src/ros2_medkit_diagnostic_bridge/src/diagnostic_bridge_node.cpp at 505bc2d5
        "diagnostics_topic",  # :42
        "auto_generate_codes",  # :43
        "use_hardware_id_as_source_id",  # :44
        "max_tracked_sources",  # :45
        "keyvalue_codes",  # :55
        "name_to_code.*",  # :64, read undeclared from the parameter overrides
        *_LOCAL_FILTER_070,
    }
)

_ACTION_STATUS_BRIDGE_070: Final = frozenset(
    {
        # src/ros2_medkit_action_status_bridge/src/action_status_bridge_node.cpp at 505bc2d5
        "aborted_severity",  # :114
        "canceled_is_fault",  # :123
        "heal_on_succeeded",  # :124
        "rescan_period_sec",  # :125
        "retry_period_sec",  # :135
        "code_prefix",  # :141
        "exclude_actions",  # :147
        "include_only_actions",  # :149
        "dedup_capacity",  # :152
        *_LOCAL_FILTER_070,  # enabled pre-declared off at :169
    }
)

_LOG_BRIDGE_070: Final = frozenset(
    {
        # src/ros2_medkit_log_bridge/src/log_bridge_node.cpp at 505bc2d5
        "rosout_topic",  # :67
        "severity_floor",  # :73
        "code_prefix",  # :82
        "exclude_nodes",  # :86
        "include_only_nodes",  # :87
        "max_tracked_nodes",  # :88
        "report_cooldown_sec",  # :102
        "exclude_medkit_stack",  # :110
        *_LOCAL_FILTER_070,
    }
)

DECLARED: Final[dict[str, dict[str, frozenset[str]]]] = {
    "0.6.0": {
        "fault_manager": _FAULT_MANAGER_060 | ROS_PARAMETERS,
        "diagnostic_bridge": _DIAGNOSTIC_BRIDGE_060 | ROS_PARAMETERS,
        "action_status_bridge": _ACTION_STATUS_BRIDGE_060 | ROS_PARAMETERS,
        "log_bridge": _LOG_BRIDGE_060 | ROS_PARAMETERS,
        "medkit_replay": _REPLAY,
    },
    "0.7.0": {
        "fault_manager": _FAULT_MANAGER_070 | ROS_PARAMETERS,
        "diagnostic_bridge": _DIAGNOSTIC_BRIDGE_070 | ROS_PARAMETERS,
        "action_status_bridge": _ACTION_STATUS_BRIDGE_070 | ROS_PARAMETERS,
        "log_bridge": _LOG_BRIDGE_070 | ROS_PARAMETERS,
        "medkit_replay": _REPLAY,
    },
}
"""Release name -> node -> the parameter names that node declares (or reads) at that release."""

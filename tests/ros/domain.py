"""A ROS 2 DDS domain of a test's own: the launcher's ``host.launch.domains`` (one copy for the
tests and the benchmarks): ``claim_domain()`` holds a free ``ROS_DOMAIN_ID`` until the block
ends, ``domain_env(d)`` is what a process needs to use it, discovering on this host only.
"""

from host.launch.domains import claim_domain, domain_env

__all__ = ["claim_domain", "domain_env"]

"""Learning a robot's model from the running robot (``dxboard model learn``) and comparing two.

A watcher (``host.learn.live`` on ROS 2 or Zenoh, ``host.learn.bagsource`` over a bag, the
tests' synthetic samples) fills a ``Recording``; ``infer`` turns it into a ``LearnedModel``
(pure functions: ``stats`` for rates, ``infer`` for structure); ``render`` writes it as the
``system.yaml`` a person reviews, with its evidence in comments; ``diff`` tells what changed
between two models. The API is ``Recording``, ``infer``, ``render`` and ``diff_models``; the
rest is internal.
"""

import os
import sys

from hypothesis import settings

sys.path.insert(0, os.path.dirname(__file__))

from common import register_profiles  # noqa: E402

register_profiles()
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if os.environ.get("CI") else "dev"))

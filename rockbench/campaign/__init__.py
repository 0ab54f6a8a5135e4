"""The campaign: one execution path (plan → references → isolated jobs → metrics → store)
that every study runs its simulations through."""

from rockbench.campaign.run import (
    Campaign,
    CampaignOptions,
    PlannedRun,
    default_timeout,
    load_trajectory,
    run_campaign,
)

__all__ = ["Campaign", "CampaignOptions", "PlannedRun", "run_campaign", "default_timeout",
           "load_trajectory"]

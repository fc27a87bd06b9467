"""The paper's comparative claims, evaluated on paired runs, with verdicts: the statements
(:mod:`~hcomc.experiments.claims.statements`) and how they are tested
(:mod:`~hcomc.experiments.claims.evaluation`)."""

from hcomc.experiments.claims.evaluation import (
    ALPHA,
    COLUMNS,
    MIN_PAIRS,
    VERDICTS,
    ci_verdict,
    claims,
    holm,
    mcnemar_exact,
    p_verdict,
    sign_test,
    verdict_counts,
)
from hcomc.experiments.claims.statements import (
    FAMILIES,
    GROUPS,
    AnyClaim,
    Claim,
    ModeClaim,
    SuccessClaim,
    all_claims,
    extension_claims,
    outcome_claims,
    paper_claims,
    replanning_claims,
)

__all__ = [
    "ALPHA",
    "COLUMNS",
    "FAMILIES",
    "GROUPS",
    "MIN_PAIRS",
    "VERDICTS",
    "AnyClaim",
    "Claim",
    "ModeClaim",
    "SuccessClaim",
    "all_claims",
    "ci_verdict",
    "claims",
    "extension_claims",
    "holm",
    "mcnemar_exact",
    "outcome_claims",
    "p_verdict",
    "paper_claims",
    "replanning_claims",
    "sign_test",
    "verdict_counts",
]

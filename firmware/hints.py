"""What a refused fit asks the user to do: the status line's and the calibration program's
hints (a reason not here is shown as is)."""
HINTS = {"planar": "rotate about another axis, not only around",
         "too_few_samples": "keep turning",
         "low_coverage": "turn through more directions",
         "fit_error_high": "move slowly, away from metal",
         "field_out_of_range": "field implausible: a magnet near, or the wrong range?",
         "field_mismatch": "field differs from the model here: wrong range, or a magnet?",
         "soft_iron_out_of_range": "strong soft iron: move away from steel",
         "inconsistent_samples": "the field changed while collecting (a magnet, a motor?): "
                                 "samples dropped, keep turning",
         "no_memory": "out of memory while solving"}

# The file-naming contract for the Makefile (docs/architecture.md, *File naming*): the same names
# as luxest-io's naming module and python/luxest_contract.py, checked against Rust's
# tests/fixtures/contract/naming.json by training/tests/test_contract.py.
#
#   $(call lx_count,64)                    000064      a count zero-padded to 6 digits
#   $(call lx_image,PREFIX,64,hdr)         PREFIX_000064spp.hdr.exr
#   $(call lx_le,PREFIX,1000,hdr)          PREFIX_001000le.hdr.exr   (double local estimate)
#   $(call lx_ref,PREFIX,hdr)              PREFIX_ref.hdr.exr

# Memoised: one shell per distinct count, not per name composed (a make run composes hundreds).
lx_count = $(or $(lx_count_$(1)),$(eval lx_count_$(1) := $(shell printf '%06d' $(1)))$(lx_count_$(1)))
lx_image = $(1)_$(call lx_count,$(2))spp.$(3).exr
lx_le = $(1)_$(call lx_count,$(2))le.$(3).exr
lx_ref = $(1)_ref.$(2).exr
#   $(call lx_realization,DIR,7)           DIR/seed7   an extra noise realization's directory
#                                                      (luxest_contract.REALIZATION_DIR)
lx_realization = $(1)/seed$(2)
#   $(call lx_own,DIR)                     DIR/own     the features at each level's own samples
#                                                      (luxest_contract.OWN_FEATURES_DIR)
lx_own = $(1)/own

# Pattern forms for rules, the level standing for %: $(call lx_image_pattern,PREFIX,dn) gives
# PREFIX_%spp.dn.exr (% = 000064), $(call lx_le_pattern,PREFIX,hdr) gives PREFIX_%le.hdr.exr.
lx_image_pattern = $(1)_%spp.$(2).exr
lx_le_pattern = $(1)_%le.$(2).exr

# The denoiser's features beside hdr, in the order of its channels, each aov-write's image of
# that kind and a `denoise --<kind>` option (python/luxest_contract.py FEATURES without hdr;
# training/tests/test_contract.py checks). aov-write writes its normal image last.
LX_FEATURES := alb nrm emi ema
# $(call lx_features,PREFIX,64): the feature images of a level, in that order.
lx_features = $(foreach k,$(LX_FEATURES),$(call lx_image,$(1),$(2),$(k)))
